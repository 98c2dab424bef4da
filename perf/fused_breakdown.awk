# Reads `perf script` output (one sample = header line + frame lines, innermost first, blank line between samples).
# For samples inside the fused substep kernel, counts the innermost drape function (SIMD wrappers skipped).
function flush() {
    if (have) {
        total++
        if (fused) { nf++; key = (leaf == "" ? "fused_block (own code)" : leaf); count[key]++ }
    }
    have = 0; fused = 0; leaf = ""
}
/^[^ \t]/ { flush(); have = 1; next }
/^[ \t]+[0-9a-f]+ / {
    s = $0
    sub(/^[ \t]+[0-9a-f]+ /, "", s)
    sub(/ \([^ ]*\)$/, "", s)
    if (s ~ /fused_block</) { fused = 1; next }
    if (!fused && leaf == "" && s ~ /^drape::/ && s !~ /^drape::simd::/) leaf = s
    next
}
END {
    flush()
    printf "samples: %d total, %d in fused_block (%.1f%%)\n", total, nf, total ? 100 * nf / total : 0
    printf "%8s %8s  %s\n", "samples", "% fused", "innermost drape function (inlined)"
    for (k in count) printf "%8d %7.1f%%  %s\n", count[k], 100 * count[k] / nf, k | "sort -rn"
}

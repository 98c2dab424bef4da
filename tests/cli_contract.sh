#!/usr/bin/env bash
# The `drape run` CLI contract, tested as users run it: every bad flag exits 2 with ONE line naming the flag and
# the allowed range; --json prints exactly one JSON object with BENCH.md's fields; help documents the flags.
set -uo pipefail
DRAPE=${DRAPE:?set DRAPE to the drape executable}
fail=0
repo=$(cd "$(dirname "$0")/.." && pwd)
err=$(mktemp)
out=$(mktemp)
log=$(mktemp)
trap 'rm -f "$err" "$out" "$log"' EXIT
# Everything printed is also kept, so the failures can be repeated together at the end (CI shows a log's tail).
exec > >(tee "$log") 2>&1

expect_exit() { # expect_exit CODE "what must appear in the message" args...: one line on stderr, never a hang
    local want_code=$1 want=$2
    shift 2
    timeout 60 "$DRAPE" "$@" >"$out" 2>"$err"
    local code=$?
    local lines
    lines=$(wc -l <"$err")
    if [ "$code" != "$want_code" ] || [ "$lines" != 1 ] || ! grep -qF -- "$want" "$err"; then
        echo "FAIL: drape $* -> exit $code, $lines line(s) on stderr, expected exit $want_code and one line with '$want':"
        cat "$err"
        fail=1
    else
        echo "ok: drape $* -> $(cat "$err")"
    fi
}
expect_error() { expect_exit 2 "$@"; } # expect_error "what must appear in the message" args...

expect_error "--size" run --size 1
expect_error "[2, 4096]" run --size 5000
expect_error "--size" run --size abc
expect_error "--size given 2 times; give it once" run --size 40 --size 9
expect_error "--threads" run --threads 0
expect_error "--dt" run --dt -1
expect_error "--self-collision" run --self-collision 0.2
expect_error "--self-collision" run --self-collision 0.0001
expect_error "--self-collision" run --self-collision abc
expect_error "--self-collision-substeps" run --self-collision-substeps 0
expect_error "--self-collision-substeps" run --self-collision-substeps 17
expect_error "stability bound" run --size 100 --dt 0.01
expect_error "--integrator" run --integrator rk4
expect_error "[100, 25000] N/m" run --stiffness 50
expect_error "--steps" run --steps 0
expect_error "--sim-seconds" run --steps 10 --sim-seconds 1
expect_error "--scene" run --scene nowhere
expect_error "--drag" run --drag -3
expect_error "--wind-strength" run --wind-strength 1e9
expect_error "--kernel" run --kernel gpu
expect_error "--foo" run --foo
expect_error "bogus" bogus

# Broken scene files: exit 2, one line naming the file and the JSON path.
tmpdir=$(mktemp -d)
trap 'rm -f "$err" "$out"; rm -rf "$tmpdir"' EXIT
echo '{"cloth": {"n": 3000000}}' >"$tmpdir/huge.json"
echo '{"cloth": {"n": 10, "colour": 1}}' >"$tmpdir/unknown.json"
echo '{"cloth": ' >"$tmpdir/malformed.json"
expect_error "cloth.n" run --scene "$tmpdir/huge.json"
expect_error "cloth.colour is not a known field" run --scene "$tmpdir/unknown.json"
expect_error "malformed JSON" run --scene "$tmpdir/malformed.json"
# A limit applied every 100 substeps blows the hang up; the advice names --strain-every (it blamed the ratio).
expect_exit 4 "applied only every 100 substeps, its corrections too large for the springs: lower physics.strain_limit.every (--strain-every" \
    run --scene hang --size 30 --strain-limit 0.01 --strain-every 100 --sim-seconds 1
expect_error "this scene has colliders; drop --fas-at-rest" run --scene sphere --solver implicit --fas-at-rest --steps 1
expect_error "--fas already runs it on every step" run --solver implicit --fas --fas-at-rest --steps 1
# Panels sewn across a gap with sewing off would snap shut and fling the cloth (found: 1.0e4 m/s, "healthy"); so
# would a seam open by a fraction of a millimetre (the bag's 5 mm: 182 m/s). Refused; without the field they are sewn.
echo '{"cloth": {"type": "outline", "outline": [[0, 0], [1, 0], [1, 1], [0, 1]], "spacing": 0.05,
                 "copy": {"gap": 0.3, "sew": [[0, 3], [3, 0]]}}, "material": "cotton_shirting",
       "physics": {"sewing_speed": 0}}' >"$tmpdir/snap.json"
expect_error "set a sewing speed (physics.sewing_speed, allowed (0, 10] m/s" run --scene "$tmpdir/snap.json" --steps 1
sed 's/"sewing_speed": 0.5,/"sewing_speed": 0,/' "$repo/scenes/examples/bag.json" >"$tmpdir/bag_unsewn.json"
expect_error "a seam is 0.005 m open (particles 0 and 666) and the sewing speed is 0" run --scene "$tmpdir/bag_unsewn.json" --steps 1
expect_error "does not exist" run --scene "$tmpdir/missing.json"
expect_error "--every" run --every 5
expect_error "--size: '3.5' must be a whole number in [2, 4096]" run --size 3.5
expect_error "--dt: value 1e400 is outside the allowed range" run --dt 1e400
expect_error "--stiffness: 'nan' is not a number" run --stiffness nan

# Found by an adversarial sweep (2026-11-25): a sliver outline's default dt (1e-21 s) is refused with its shortest
# spring, not run as 0 substeps; a run whose last steps blow up between the monitor's checks is not reported healthy
# (the end state is checked), and an implicit blow-up names the solver's own cause.
echo '{"cloth": {"type": "outline", "outline": [[0,0],[1,0],[0.5,1e-6]], "spacing": 0.01}, "material": "wool"}' \
    >"$tmpdir/sliver.json"
expect_error "below the smallest dt (1e-9 s): its shortest spring is" run --scene "$tmpdir/sliver.json" --sim-seconds 0.2
expect_error "(a near-degenerate triangle or two vertices almost on top of each other): remesh the cloth" run --scene "$tmpdir/sliver.json" --sim-seconds 0.2
# Found by an adversarial sweep (2026-12-01): a regular grid of a light fabric whose damping sets a bound below 1e-9 s
# was blamed on its mesh ("remesh the cloth"); the damping is named, with its range.
echo '{"cloth": {"type": "grid", "n": 100, "size": 0.05, "pins": "corners"},
       "material": {"density_gsm": 5, "stretch_u": 10, "stretch_v": 10, "shear": 0.01, "bend_u_uNm": 0,
                    "bend_v_uNm": 0, "damping": 0.1}}' >"$tmpdir/damped.json"
expect_error "below the smallest dt (1e-9 s): the damping sets that bound" run --scene "$tmpdir/damped.json"
expect_error "(material.damping: [0, 0.1] s); or use --solver implicit" run --scene "$tmpdir/damped.json"
echo '{"cloth": {"type": "grid", "n": 24, "pins": "corners"}, "material": "wool",
       "physics": {"solver": "implicit", "implicit": {"chebyshev_rho": 0.999999}}}' >"$tmpdir/rho.json"
expect_exit 4 "likely cause: Chebyshev acceleration amplifying the sweeps (physics.implicit.chebyshev_rho = 0.999999)" \
    run --scene "$tmpdir/rho.json" --steps 4
# (Two lines: the warning at the start that the thickness is above half the spacing, then the blow-up.)
timeout 60 "$DRAPE" run --size 32 --self-collision 0.05 --steps 127 >"$out" 2>"$err"
code=$?
if [ "$code" = 4 ] && [ "$(wc -l <"$err")" = 2 ] && grep -qF "warning: self-collision's thickness (0.05 m) is above half" "$err" &&
    grep -qF "likely cause: self-collision's thickness (0.05 m)" "$err"; then
    echo "ok: drape run --size 32 --self-collision 0.05 --steps 127 -> warned, then exit 4 naming self-collision"
else
    echo "FAIL: drape run --size 32 --self-collision 0.05 --steps 127 -> exit $code:"; cat "$err"; fail=1
fi

# Flags that would change nothing in the run are refused (they were accepted and echoed in the JSON while ignored).
expect_error "--self-collision-substeps: a flag of the implicit solver's self-collision" run --self-collision-substeps 3
expect_error "--self-collision-substeps: self-collision is off" run --solver implicit --self-collision-substeps 3
expect_error "--strain-passes: strain limiting is off" run --strain-passes 7
expect_error "--strain-every: strain limiting is off" run --strain-every 3
expect_error "--wind-strength: the wind is off" run --wind-strength 50
expect_error "--kernel csr: a choice of the explicit solver" run --solver implicit --kernel csr --steps 1
expect_error "--staged: a choice of the explicit solver" run --solver implicit --staged --steps 1
expect_error "--dt: 1e-05 s is below the implicit solver's shortest step, 1e-4 s" run --solver implicit --dt 1e-5 --steps 1
expect_error "but the multilevel guess is off (--single-level)" run --solver implicit --fas --single-level --steps 1
expect_error "but this cloth has no coarse levels" run --scene tshirt --solver implicit --fas --steps 1
expect_error "--fas-at-rest: the coarse correction of the multilevel guess, but the multilevel guess is off (--single-level)" \
    run --solver implicit --fas-at-rest --single-level --steps 1
expect_error "--fas-at-rest: the coarse correction of the multilevel guess, but this cloth has no coarse levels" \
    run --scene tshirt --solver implicit --fas-at-rest --steps 1
expect_error "--fas-at-rest: a flag of the implicit solver, but the solver is explicit" run --fas-at-rest

expect_error "--export-obj: an empty path" run --steps 1 --export-obj ''
expect_error "--sim-seconds 10 at dt = 1e-09 s needs 1e+10 substeps (max 1e9)" run --dt 1e-9 --sim-seconds 10

# Meshes beyond what float arithmetic carries: refused with the figure (were inf strain, NaN normals, exit 0).
printf 'v 0 0 0\nv 1e30 0 0\nv 0 0 1e30\nf 1 2 3\n' >"$tmpdir/huge.obj"
echo '{"cloth": {"type": "mesh", "file": "huge.obj", "pins": "none"}, "material": "wool"}' >"$tmpdir/huge_mesh.json"
expect_error "cloth.file: the mesh reaches 5e+29 m from its centre after cloth.scale (at most 1e4 m)" \
    run --scene "$tmpdir/huge_mesh.json" --steps 1
printf 'v 0 0 0\nv 1 0 0\nv 0 0 1\nv -1e-7 0 0\nf 1 2 3\nf 1 3 4\n' >"$tmpdir/near.obj"
echo '{"cloth": {"type": "mesh", "file": "near.obj", "pins": "none"}, "material": "wool"}' >"$tmpdir/near_mesh.json"
expect_exit 2 "the mesh's shortest edge is" run --scene "$tmpdir/near_mesh.json" --steps 1

# Numbers a double cannot hold, NaN and Infinity: a range error naming the file and the JSON path, never an abort.
echo '{"cloth": {"n": 1e400}}' >"$tmpdir/overflow.json"
echo '{"physics": {"gravity": [0, -1e400, 0]}}' >"$tmpdir/gravity.json"
printf '{"cloth": {"n": 1%0400d}}\n' 0 >"$tmpdir/digits.json"
echo '{"cloth": {"size": NaN}}' >"$tmpdir/nan.json"
echo '{"material": {"stiffness": Infinity}}' >"$tmpdir/inf.json"
expect_error "overflow.json: cloth.n = 1e400 is not a finite number; allowed range [2, 4096]" run --scene "$tmpdir/overflow.json"
expect_error "gravity.json: physics.gravity[1] = -1e400 is not a finite number; allowed range [-100, 100] m/s^2" \
    run --scene "$tmpdir/gravity.json"
expect_error "digits.json: cloth.n = 10000000000" run --scene "$tmpdir/digits.json"
expect_error "nan.json: cloth.size = NaN is not a finite number; allowed range [0.01, 100] m" run --scene "$tmpdir/nan.json"
expect_error "inf.json: material.stiffness = Infinity is not a finite number" run --scene "$tmpdir/inf.json"
echo '{"cloth": {"n": 2, "size": 0.1}, "material": "wool", "state": {"positions": [[NaN, 0, 0], [0.1, 0, 0], [0, 0, 0.1], [0.1, 0, 0.1]], "velocities": [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]], "pinned": []}}' >"$tmpdir/state_nan.json"
expect_error "state.positions[0][0] = NaN is not a finite number; allowed range [-1e+06, 1e+06] m" run --scene "$tmpdir/state_nan.json"

# The scene path is checked before it is opened: a FIFO does not hang, a directory is not "larger than 16 MiB".
mkfifo "$tmpdir/fifo.json"
mkdir "$tmpdir/dir.json"
head -c $((16 * 1024 * 1024 + 1)) /dev/zero >"$tmpdir/big.json"
expect_error "fifo.json: is not a regular file (a FIFO)" run --scene "$tmpdir/fifo.json"
expect_error "dir.json: is a directory" run --scene "$tmpdir/dir.json"
expect_error "big.json: the file is 16777217 bytes (16.00 MiB); scene files are limited to 16 MiB (16777216 bytes)" run --scene "$tmpdir/big.json"
cp "$tmpdir/unknown.json" "$tmpdir/locked.json"
chmod 000 "$tmpdir/locked.json"
if [ "$(id -u)" != 0 ]; then
    expect_error "locked.json: the scene file cannot be read (permission denied)" run --scene "$tmpdir/locked.json"
elif command -v setpriv >/dev/null && setpriv --reuid=65534 --regid=65534 --clear-groups "$DRAPE" --version >/dev/null 2>&1; then
    # root reads anything: the check runs as nobody
    chmod 711 "$tmpdir"
    DRAPE_AS_ROOT=$DRAPE
    printf '#!/bin/sh\nexec setpriv --reuid=65534 --regid=65534 --clear-groups "%s" "$@"\n' "$DRAPE" >"$tmpdir/as_nobody"
    chmod 755 "$tmpdir/as_nobody"
    DRAPE="$tmpdir/as_nobody"
    expect_error "locked.json: the scene file cannot be read (permission denied)" run --scene "$tmpdir/locked.json"
    DRAPE=$DRAPE_AS_ROOT
    chmod 700 "$tmpdir"
else
    echo "skip: unreadable scene file (running as root without setpriv)"
fi

# Outlines: a self-crossing outline is named as such; a limit or a thin outline names the file and the field.
echo '{"cloth": {"type": "outline", "outline": [[0,0],[1,1],[1,0],[0,1]]}}' >"$tmpdir/bowtie.json"
echo '{"cloth": {"type": "outline", "outline": [[0,0],[50,0],[50,50],[0,50]], "spacing": 0.02}}' >"$tmpdir/many.json"
echo '{"cloth": {"type": "outline", "outline": [[0,0],[1,0],[1,1e-9]], "spacing": 0.3}}' >"$tmpdir/thin.json"
expect_error "bowtie.json: cloth.outline: outline is self-intersecting: edge 0 (vertices 0-1) meets edge 2" \
    run --scene "$tmpdir/bowtie.json"
expect_error "many.json: cloth.spacing = 0.02 m gives this outline up to 626" \
    run --scene "$tmpdir/many.json"
expect_error "points per panel; at most 4000000 are allowed (raise the spacing)" run --scene "$tmpdir/many.json"
expect_error "thin.json: cloth.outline at cloth.spacing = 0.3 m: outline panel has no triangle" run --scene "$tmpdir/thin.json"

# dt above the bound names where it came from; the bound as printed (JSON or text) is accepted back as --dt.
echo '{"cloth": {"n": 100}, "physics": {"dt": 0.01}}' >"$tmpdir/dt.json"
expect_error "dt.json: physics.dt = 0.01 s is above the explicit stability bound" run --scene "$tmpdir/dt.json"
expect_error "--dt = 0.01 s is above the explicit stability bound" run --size 100 --dt 0.01
json_bound=$("$DRAPE" run --size 100 --steps 1 --json | python3 -c "import json,sys; print(json.load(sys.stdin)['dt_max'])")
text_bound=$("$DRAPE" run --size 100 --steps 1 | sed -n 's/.*bound \([0-9.e+-]*\) s).*/\1/p')
for b in "$json_bound" "$text_bound"; do
    if "$DRAPE" run --size 100 --steps 5 --dt "$b" >"$out" 2>"$err"; then
        echo "ok: the printed bound $b is accepted as --dt"
    else
        echo "FAIL: the printed bound '$b' is refused as --dt:"; cat "$err"; fail=1
    fi
done

# The implicit solver: bad values exit 2 with one line naming the flag or the file's field; --dt is not held to the
# explicit bound; a good run reports the solver, its iterations and residual, and the real-time factor.
expect_error "--solver: newton not in {explicit,implicit}" run --solver newton
expect_error "--iterations: value 0 is outside the allowed range [1, 1000]" run --solver implicit --iterations 0
expect_error "--iterations: '2.5' must be a whole number in [1, 1000]" run --solver implicit --iterations 2.5
expect_error "--tolerance: value 2 is outside the allowed range [0, 1]" run --solver implicit --tolerance 2
expect_error "--dt: value 0.5 is outside the allowed range" run --solver implicit --dt 0.5
expect_error "--iterations: a flag of the implicit solver, but the solver is explicit" run --iterations 10
expect_error "--single-level: a flag of the implicit solver, but the solver is explicit" run --single-level
expect_error "--single-level: a flag of the implicit solver, but the solver is explicit" view --single-level
expect_error "--integrator: verlet is a choice of the explicit solver only" run --solver implicit --integrator verlet
expect_error "--iterations: value 5000 is outside the allowed range [1, 1000]" view --iterations 5000
expect_error "--solver: rk4 not in {explicit,implicit}" view --solver rk4
expect_error "--camera-yaw: value 400 is outside the allowed range [-360, 360] degrees" view --camera-yaw 400
expect_error "--camera-yaw: 'nan' is not a number" view --camera-yaw nan
echo '{"physics": {"solver": "implicit", "integrator": "verlet"}}' >"$tmpdir/implicit_verlet.json"
echo '{"physics": {"solver": "implicit", "implicit": {"chebyshev_rho": 1}}}' >"$tmpdir/implicit_rho.json"
expect_error "implicit_verlet.json: physics.integrator = \"verlet\" is a choice of the explicit solver only" \
    run --scene "$tmpdir/implicit_verlet.json"
expect_error "implicit_rho.json: physics.implicit.chebyshev_rho = 1 is outside the allowed range [0, 1)" \
    run --scene "$tmpdir/implicit_rho.json"
if "$DRAPE" run --solver implicit --size 100 --sim-seconds 0.2 --dt 0.05 --iterations 20 --json >"$out" 2>"$err" &&
    python3 - "$out" <<'PY'; then
import json, math, sys
j = json.load(open(sys.argv[1]))
assert j["solver"] == "implicit" and j["integrator"] == "euler", j
assert j["steps"] == j["substeps"] == 4 and abs(j["dt"] - 0.05) < 1e-9 and j["dt"] > j["dt_max"], j
im = j["implicit"]
assert 1 <= im["iterations"] <= 20 and im["max_iterations"] == 20 and im["method"] == "gauss_seidel", im
assert im["multilevel"] is True and im["levels"] > 1 and im["levels_available"] == im["levels"], im  # a 100 x 100 fabric grid: the multilevel guess
assert math.isfinite(im["relative_residual"]) and im["relative_residual"] >= 0, im
assert j["real_time_factor"] > 0 and j["finite"] and j["healthy"], j
print("ok: drape run --solver implicit --size 100 --dt 0.05 -> %d iterations, residual %.3g, %.3gx real time"
      % (im["iterations"], im["relative_residual"], j["real_time_factor"]))
PY
    :
else
    echo "FAIL: an implicit run"; cat "$err" "$out"; fail=1
fi
# The built-in T-shirt is mirror-exact; a scene that switches it off says so.
plain=$(mktemp --suffix=.json)
printf '{"cloth": {"type": "tshirt", "mirror_exact": false}}' > "$plain"
if "$DRAPE" run --scene tshirt --steps 1 --json 2>/dev/null | python3 -c "import json,sys; j=json.load(sys.stdin); assert j['mirror_exact'] is True, j.get('mirror_exact')" &&
   "$DRAPE" run --scene "$plain" --steps 1 --json 2>/dev/null | python3 -c "import json,sys; j=json.load(sys.stdin); assert j['mirror_exact'] is False, j.get('mirror_exact')"; then
    echo "ok: the T-shirt reports mirror_exact (true by default, false when its scene switches it off)"
else
    echo "FAIL: the T-shirt's mirror_exact in the JSON"; fail=1
fi
rm -f "$plain"
# A cloth without coarse levels says so beside the setting (an adversarial sweep read "multilevel": true, "levels": 1).
if "$DRAPE" run --scene tshirt --solver implicit --steps 1 --json 2>/dev/null | python3 -c "import json,sys; im=json.load(sys.stdin)['implicit']; assert im['multilevel'] is True and im['levels_available'] == 1 and im['levels'] == 1, im"; then
    echo "ok: the T-shirt's implicit JSON reports the multilevel setting with no coarse levels available"
else
    echo "FAIL: the T-shirt's implicit levels fields"; fail=1
fi
if "$DRAPE" run --steps 3 --json | python3 -c "import json,sys; j=json.load(sys.stdin); assert j['solver']=='explicit' and 'implicit' not in j and j['real_time_factor'] > 0, j"; then
    echo "ok: an explicit run reports solver explicit and its real-time factor"
else
    echo "FAIL: the explicit run's solver fields"; fail=1
fi

# Output that cannot be written: exit 5 with one line.
expect_exit 5 "--export-obj: cannot create directory" run --steps 1 --export-obj /dev/null/frames

# drape view: a screenshot that cannot be written is exit 5 with one line (needs the viewer and Xvfb).
# A private Xvfb (scripts/with_xvfb.sh): xvfb-run exits 5 with a line of its own when it cannot remove its temporary
# directory, which once failed this check under CI's load.
with_xvfb="$(cd "$(dirname "$0")/.." && pwd)/scripts/with_xvfb.sh"
if command -v Xvfb >/dev/null && "$DRAPE" view --help >/dev/null 2>&1 &&
    ! "$DRAPE" view --frames 1 2>&1 | grep -q "this build has no viewer"; then
    # Under ASan the GL driver (Mesa's llvmpipe, dlopen'ed, so "<unknown module>" in the report) leaves 56-byte
    # calloc blocks that LeakSanitizer reports at this early exit; this check is about the exit code and the message,
    # drape's own allocations are leak-checked by the gtest suite.
    ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
        "$with_xvfb" -s "-screen 0 1280x800x24" "$DRAPE" view --frames 3 --screenshot /dev/null/x.png >"$out" 2>"$err"
    code=$?
    if [ "$code" = 5 ] && [ "$(wc -l <"$err")" = 1 ] && grep -qF "cannot write the screenshot /dev/null/x.png" "$err"; then
        echo "ok: drape view --screenshot /dev/null/x.png -> $(cat "$err")"
    else
        echo "FAIL: drape view with an unwritable screenshot -> exit $code, expected 5 and one line:"; cat "$err"; fail=1
    fi
else
    echo "skip: drape view exit codes (no viewer in this build, or no Xvfb)"
fi

# Memory is checked before a big build: refused at once with the figure (ulimit -v makes it the same on any machine).
# AddressSanitizer reserves terabytes of shadow address space at start, which no ulimit -v admits: not under ASan.
# readelf reads the binary's dynamic section without running the loader (ldd once said no here under CI's load).
if readelf -d "$DRAPE" 2>/dev/null | grep -q 'libasan'; then
    echo "skip: the ulimit -v memory refusal (an ASan build cannot start under ulimit -v)"
else
    (
        ulimit -v 4000000
        expect_error "--size 4096: the cloth would have 16777216 particles and needs about" run --size 4096
        exit $fail
    ) || fail=1
fi

# --size on an outline cloth sets its spacing (1 / cells per metre), as the viewer's slider does; the JSON reports it.
echo '{"cloth": {"type": "outline", "outline": [[0,0],[0.3,0],[0,0.3]]}}' >"$tmpdir/tri.json"
"$DRAPE" run --scene "$tmpdir/tri.json" --steps 2 --json >"$out.own" 2>"$err" || { echo "FAIL: outline run"; cat "$err"; fail=1; }
"$DRAPE" run --scene "$tmpdir/tri.json" --size 50 --steps 2 --json >"$out" 2>"$err" || { echo "FAIL: outline --size run"; cat "$err"; fail=1; }
if [ ! -s "$err" ] &&
    python3 -c "import json,sys; o=json.load(open('$out.own')); j=json.load(open('$out')); assert j['cloth']=='outline' and abs(j['spacing']-0.02)<1e-9 and abs(o['spacing']-0.03)<1e-9 and j['particles']>o['particles'] and 'size_ignored' not in j, (o, j)"; then
    echo "ok: --size 50 on an outline -> spacing 0.02 m, $(python3 -c "import json; print(json.load(open('$out.own'))['particles'], '->', json.load(open('$out'))['particles'])") particles"
else
    echo "FAIL: --size on an outline cloth does not set its spacing"; cat "$err" "$out"; fail=1
fi
rm -f "$out.own"
expect_error "--size: value 5 is outside the allowed range [10, 1000] (cells per metre of the outline" run --scene "$tmpdir/tri.json" --size 5

# Mask cloths (cloth.type "mask"): the example runs; broken files each give their one-line error, exit 2.
"$DRAPE" run --scene "$repo/scenes/examples/tank_top.json" --steps 20 --json >"$out" 2>"$err" || { echo "FAIL: tank_top run"; cat "$err"; fail=1; }
python3 -c "import json; j=json.load(open('$out')); assert j['cloth']=='mask' and j['panels']==2 and j['particles']==1450 and j['seam_springs']==62 and j['finite'], j; print('ok: tank_top.json ->', j['particles'], 'particles,', j['seam_springs'], 'seam springs')" || fail=1
expect_error "--size: the scene's cloth is made of masks" run --scene "$repo/scenes/examples/tank_top.json" --size 50
mask() { # mask NAME 'panels' 'seams': a mask scene file in $tmpdir
    echo "{\"cloth\": {\"type\": \"mask\", \"panels\": [$2], \"seams\": [$3]}}" >"$tmpdir/$1.json"
}
P_A='{"name": "a", "rows": ["111", "111", "111"]}'
P_B='{"name": "b", "rows": ["111", "111", "111"], "origin": [0, 0, 0.1]}'
mask unequal '{"name": "a", "rows": ["111", "11"]}' ''
expect_error "unequal.json: cloth.panels[0].rows[1] has 2 characters but cloth.panels[0].rows[0] has 3 (a mask is rectangular" run --scene "$tmpdir/unequal.json"
mask letters '{"name": "a", "rows": ["1x1"]}' ''
expect_error "letters.json: cloth.panels[0].rows[0] column 1 holds 'x'; only '0' and '1' are allowed" run --scene "$tmpdir/letters.json"
mask empty "$P_A"', {"name": "b", "rows": ["000", "000"]}' ''
expect_error "empty.json: cloth.panels[1].rows holds no '1': a panel needs at least one particle" run --scene "$tmpdir/empty.json"
mask lengths "$P_A, $P_B" '{"a": {"panel": "a", "path": [[0, 0], [0, 2]]}, "b": {"panel": "b", "path": [[0, 0], [0, 1]]}}'
expect_error "lengths.json: cloth.seams[0].b.path has 2 cells but cloth.seams[0].a.path has 3; a seam joins two edges cell to cell" run --scene "$tmpdir/lengths.json"
mask inside "$P_A, $P_B" '{"a": {"panel": "a", "path": [[1, 0], [1, 2]]}, "b": {"panel": "b", "path": [[0, 0], [0, 2]]}}'
expect_error "inside.json: cloth.seams[0].a.path passes cell [1, 1], inside panel \"a\": an edge runs along the panel's boundary" run --scene "$tmpdir/inside.json"
mask unknown "$P_A" '{"a": {"panel": "a", "path": [[0, 0]]}, "b": {"panel": "c", "path": [[2, 2]]}}'
expect_error "unknown.json: cloth.seams[0].b.panel = \"c\" is not a panel of this cloth (\"a\")" run --scene "$tmpdir/unknown.json"
mask cell '{"name": "a", "rows": ["1"], "cell_size": 2}' ''
expect_error "cell.json: cloth.panels[0].cell_size = 2 is outside the allowed range [0.001, 1] m" run --scene "$tmpdir/cell.json"

# The progress line (a terminal only) is erased before the summary, not left above it.
if command -v script >/dev/null; then
    DRAPE_PROGRESS_AFTER=0 script -qec "$DRAPE run --size 20 --steps 3000" /dev/null >"$out" 2>&1
    if python3 - "$out" <<'PY'; then
import sys
text = open(sys.argv[1], "rb").read()
progress = text.rfind(b"drape: substep")
summary = text.find(b"drape run: scene")
assert progress >= 0, "no progress line shown on the terminal"
assert summary > progress, "the summary came before the progress line"
assert b"\r\x1b[K" in text[progress:summary], "the progress line is not erased before the summary: %r" % text[progress:summary]
PY
        echo "ok: the progress line is erased before the summary"
    else
        fail=1
    fi
else
    echo "skip: progress line (no 'script' to run on a terminal)"
fi
expect_error "[10, 1000]" run --scene tshirt --size 5

# Every built-in scene runs and reports; OBJ frames are written.
for scene in hang drape sphere flag tshirt; do
    if ! "$DRAPE" run --scene "$scene" --steps 20 --json >"$out" 2>"$err"; then
        echo "FAIL: scene $scene"; cat "$err"; fail=1
    else
        echo "ok: scene $scene -> $(python3 -c "import json; j=json.load(open('$out')); print(j['particles'], 'particles', '+'.join(j['stages']))")"
    fi
done
"$DRAPE" run --scene sphere --steps 30 --export-obj "$tmpdir/obj" --every 10 --json >"$out" 2>"$err" || { echo "FAIL: --export-obj"; cat "$err"; fail=1; }
frames=$(ls "$tmpdir/obj" | wc -l)
if [ "$frames" != 4 ] || ! grep -q "^f " "$tmpdir/obj/frame_00003.obj"; then
    echo "FAIL: --export-obj wrote $frames frames (expected 4: initial + 3)"; fail=1
else
    echo "ok: --export-obj -> $frames frames"
fi
# A directory that already holds frames is refused (a later, shorter run overwrote some and left the rest: a mixed
# sequence, and a user's own frame_00000.obj lost); --overwrite removes them all first and touches nothing else.
echo "mine" >"$tmpdir/obj/notes.txt"
expect_error "already holds 4 frame_*.obj files (frame_00000.obj ... frame_00003.obj); choose an empty or new directory, or add --overwrite" \
    run --scene sphere --steps 5 --export-obj "$tmpdir/obj"
"$DRAPE" run --scene sphere --steps 5 --export-obj "$tmpdir/obj" --overwrite >"$out" 2>"$err"
if [ $? != 0 ] || [ "$(ls "$tmpdir/obj" | tr '\n' ' ')" != "frame_00000.obj frame_00001.obj notes.txt " ]; then
    echo "FAIL: --overwrite left: $(ls "$tmpdir/obj" | tr '\n' ' ')"; cat "$err"; fail=1
else
    echo "ok: --export-obj --overwrite -> $(ls "$tmpdir/obj" | tr '\n' ' ')"
fi
expect_error "--overwrite" run --steps 1 --overwrite

# A mesh cloth from an OBJ file (scenes/examples/mesh_disc.json -> tests/data/disc.obj, 469 vertices) runs and exports
# (0.1 s: 2,268 steps, 24 frames; 0.5 s took 48 s under ASan).
if ! "$DRAPE" run --scene "$repo/scenes/examples/mesh_disc.json" --sim-seconds 0.1 --export-obj "$tmpdir/mesh" \
        --json >"$out" 2>"$err" || [ -s "$err" ]; then
    echo "FAIL: mesh_disc run"; cat "$err"; fail=1
fi
mesh_frames=$(ls "$tmpdir/mesh" 2>/dev/null | wc -l)
last=$(ls "$tmpdir/mesh" 2>/dev/null | tail -1)
if [ "$mesh_frames" -lt 2 ] || [ "$(grep -c '^v ' "$tmpdir/mesh/$last")" != 469 ] || \
   [ "$(grep -c '^f ' "$tmpdir/mesh/$last")" != 864 ] || \
   ! python3 -c "import json,sys; j=json.load(open('$out')); assert j['particles'] == 469 and j['finite'] is True, j"; then
    echo "FAIL: mesh_disc export: $mesh_frames frames, last $last"; fail=1
else
    echo "ok: mesh_disc -> $mesh_frames OBJ frames of 469 vertices, 864 triangles"
fi
# Broken OBJ files: exit 2, one line naming the scene, cloth.file and what is wrong.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n' >"$tmpdir/range.obj"
printf 'this is not\x01 an OBJ file\n' >"$tmpdir/garbage.obj"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n' >"$tmpdir/noface.obj"
printf 'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n' >"$tmpdir/nan.obj"
for obj in missing range garbage noface nan; do
    echo "{\"cloth\": {\"type\": \"mesh\", \"file\": \"$obj.obj\"}}" >"$tmpdir/mesh_$obj.json"
done
expect_error "mesh_missing.json: cloth.file \"missing.obj\": $tmpdir/missing.obj: cannot open the OBJ file" \
    run --scene "$tmpdir/mesh_missing.json"
expect_error "range.obj: line 5: face vertex index 7 is outside [1, 3]" run --scene "$tmpdir/mesh_range.json"
expect_error "garbage.obj: no triangle (the file has no faces" run --scene "$tmpdir/mesh_garbage.json"
expect_error "noface.obj: no triangle (the file has no faces" run --scene "$tmpdir/mesh_noface.json"
expect_error "nan.obj: line 2: vertex coordinate 'nan' is not a finite number" run --scene "$tmpdir/mesh_nan.json"
expect_error "--size: the scene's cloth is a mesh" run --scene "$repo/scenes/examples/mesh_disc.json" --size 50

# --json: exactly one JSON object with the BENCH.md fields.
if ! "$DRAPE" run --scene hang --size 40 --threads 2 --steps 50 --json >"$out" 2>"$err"; then
    echo "FAIL: --json run exited non-zero"; cat "$err"; fail=1
fi
python3 - "$out" <<'PY' || fail=1
import json, sys
text = open(sys.argv[1]).read()
lines = [l for l in text.splitlines() if l.strip()]
assert len(lines) == 1, f"expected one line of JSON, got {len(lines)}"
j = json.loads(lines[0])
need = ["scene", "n", "particles", "springs", "threads", "substeps", "dt", "wall_seconds",
        "particle_substeps_per_second", "stages", "max_strain", "finite", "checksum"]
missing = [k for k in need if k not in j]
assert not missing, f"missing fields {missing}"
assert j["n"] == 40 and j["particles"] == 1600 and j["substeps"] == 50 and j["threads"] == 2, j
assert j["springs"] == 2*40*39 + 2*39*39, j["springs"]  # the hang scene's fabric: structural + shear, no bend springs
assert j["finite"] is True and len(j["checksum"]) == 16, j
print("ok: --json ->", {k: j[k] for k in ("particles", "springs", "substeps", "checksum")})
PY

# --threads runs that many workers (also above the core count) and the JSON reports them; same checksum as 1.
"$DRAPE" run --size 40 --steps 50 --threads 8 --json >"$out" 2>"$err" || { echo "FAIL: --threads 8"; cat "$err"; fail=1; }
"$DRAPE" run --size 40 --steps 50 --threads 1 --json >"$out.1" 2>"$err" || { echo "FAIL: --threads 1"; cat "$err"; fail=1; }
python3 - "$out" "$out.1" <<'PY' || fail=1
import json, sys
j, one = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert j["threads"] == 8 and one["threads"] == 1 and j["hardware_threads"] >= 1, (j, one)
assert j["checksum"] == one["checksum"], (j["checksum"], one["checksum"])
print("ok: --threads 8 ->", j["threads"], "workers on", j["hardware_threads"], "hardware threads, checksum", j["checksum"])
PY
rm -f "$out.1"
# Health monitor (docs/user_guide.md "Health monitor"): the issue-10 blow-ups now run healthy, exit 0, and the JSON
# says what the strain limit honoured. (Exit code 4 - BlowUpError - is tested in tests/test_health.cpp on a
# constructed explosion: no in-range flag or scene file blows up any more, so none can trigger it from here.)
check_health() { # check_health "python condition on j" args...
    local cond=$1
    shift
    "$DRAPE" run "$@" --json >"$out" 2>"$err"
    local code=$?
    if [ "$code" != 0 ] || ! python3 -c "import json,sys; j=json.load(open('$out')); sys.exit(0 if ($cond) else 1)"; then
        echo "FAIL: drape run $* -> exit $code, expected 0 and $cond:"; cat "$out" "$err"; fail=1
    else
        echo "ok: drape run $* -> $(python3 -c "import json; j=json.load(open('$out')); print({k: j.get(k) for k in ('healthy', 'kinetic_energy', 'strain_limit_max_stretch', 'strain_limit_honoured')})")"
    fi
}
check_health "j['healthy'] and j['strain_limit_honoured'] and j['strain_limit_max_stretch'] <= 0.011 and j['kinetic_energy'] < 1 and j['health']['energy_bound'] > 0" \
    --size 32 --material springs --stiffness 100 --strain-limit 0.01 --sim-seconds 0.5
# A run that ends with springs strained past 100 % says so (an adversarial sweep's soft, heavy custom fabric ended at
# strain 8-34 "healthy" and silent): exit 0, the JSON's overstretched, one warning naming the causes and the limit.
echo '{"cloth": {"type": "grid", "n": 8, "size": 1, "pins": "corners"},
       "material": {"density_gsm": 2000, "stretch_u": 10, "stretch_v": 10, "shear": 0.01, "bend_u_uNm": 0,
                    "bend_v_uNm": 0, "damping": 0}}' >"$tmpdir/soft_heavy.json"
"$DRAPE" run --scene "$tmpdir/soft_heavy.json" --steps 500 --json >"$out" 2>"$err"
code=$?
if [ "$code" = 0 ] && [ "$(wc -l <"$err")" = 1 ] && grep -qF "far past what a woven or knitted fabric survives" "$err" &&
    grep -qF "a strain limit (--strain-limit, physics.strain_limit.ratio, allowed [0, 10]) bounds it" "$err" &&
    python3 -c "import json; j=json.load(open('$out')); assert j['overstretched'] and j['max_strain'] > 1, j"; then
    echo "ok: overstretched run -> $(cat "$err")"
else
    echo "FAIL: overstretched run: exit $code"; cat "$err" "$out"; fail=1
fi
check_health "j['healthy'] and not j['overstretched']" --scene hang --size 32 --sim-seconds 0.5
# Seams that start open are sewn by default (0.5 m/s): the bag without its sewing_speed field (seams 5 mm open) and
# the square sewn to its copy across 0.3 m move gently from the first substep (snapped: 182 m/s and 1.0e4 m/s).
sed 's/"sewing_speed": 0.5,//' "$repo/scenes/examples/bag.json" >"$tmpdir/bag_default.json"
check_health "j['healthy'] and j['max_speed'] < 1" --scene "$tmpdir/bag_default.json" --steps 1
echo '{"cloth": {"type": "outline", "outline": [[0, 0], [1, 0], [1, 1], [0, 1]], "spacing": 0.05,
                 "copy": {"gap": 0.3, "sew": [[0, 3], [3, 0]]}}, "material": "cotton_shirting"}' >"$tmpdir/snap_default.json"
check_health "j['healthy'] and j['max_speed'] < 1" --scene "$tmpdir/snap_default.json" --sim-seconds 0.2
cat >"$tmpdir/overlap.json" <<'JSON'
{ "cloth": {"type": "grid", "n": 20, "size": 1.0, "plane": "horizontal", "centre": [0, 0, 0], "pins": "none"},
  "material": {"damping_ratio": 0}, "physics": {"drag": 0},
  "colliders": [ {"type": "sphere", "centre": [-0.1, 0, 0], "radius": 0.2, "thickness": 0.1, "friction": 0},
                 {"type": "sphere", "centre": [0.1, 0, 0], "radius": 0.2, "thickness": 0.1, "friction": 0} ] }
JSON
check_health "j['healthy'] and j['finite'] and j['kinetic_energy'] < 0.49 and 'health_error' not in j" \
    --scene "$tmpdir/overlap.json" --sim-seconds 2

# --sim-seconds converts to substeps of the default dt.
"$DRAPE" run --size 20 --sim-seconds 0.05 --json >"$out" 2>"$err" || { echo "FAIL: --sim-seconds"; cat "$err"; fail=1; }
python3 -c "import json,sys; j=json.load(open('$out')); assert abs(j['sim_seconds']-0.05) < j['dt']+1e-9, j; print('ok: --sim-seconds ->', j['substeps'], 'substeps')" || fail=1

# Materials: --material takes a fabric preset or springs; the spring flags are refused for a fabric; the run's JSON
# reports the model, the fabric's figures and the derived per-element values; `drape materials` lists the presets.
expect_error "--material: 'velvet' is not a material (fabric presets: silk, cotton_shirting" run --material velvet
expect_error "--stiffness: a spring-model flag, but the material is the fabric 'denim'" run --material denim --stiffness 2000
expect_error "add --material springs" run --scene hang --damping 0.1
echo '{"cloth": {"type": "grid", "n": 8}, "material": {"fabric": "silk", "bend_u_uNm": -1}}' >"$tmpdir/bend.json"
expect_error "bend.json: material.bend_u_uNm = -1 is outside the allowed range [0, 10000] micro-N*m" run --scene "$tmpdir/bend.json"
echo '{"cloth": {"type": "grid", "n": 8}, "material": {"fabric": "silk", "stiffness": 2000}}' >"$tmpdir/mixed.json"
expect_error "material.fabric is a fabric field but material.stiffness is a spring-model field" run --scene "$tmpdir/mixed.json"
"$DRAPE" run --size 12 --material denim --steps 5 --json >"$out" 2>"$err" || { echo "FAIL: run --material denim"; cat "$err"; fail=1; }
python3 - "$out" <<'PY' || fail=1
import json, sys
j = json.load(open(sys.argv[1]))
m = j["material"]
assert m["model"] == "fabric" and m["fabric"]["name"] == "denim", m
assert abs(m["fabric"]["density_gsm"] - 270) < 1e-3 and m["fabric"]["bend_u_uNm"] > 0, m
d = m["derived"]
assert d["node_mass_g"] > 0 and all(k in d["spring_k"] for k in ("structural", "shear", "bend", "seam")), d
print("ok: run --material denim ->", m["model"], m["fabric"]["name"], "node mass", d["node_mass_g"], "g, k", d["spring_k"])
PY
"$DRAPE" run --size 12 --material springs --steps 5 --json >"$out" 2>"$err" || { echo "FAIL: run --material springs"; cat "$err"; fail=1; }
python3 -c "import json,sys; j=json.load(open('$out')); m=j['material']; assert m['model']=='springs' and j['stiffness']==m['stiffness'] and m['derived']['spring_k']['structural']==m['stiffness'], m; print('ok: run --material springs ->', m['derived'])" || fail=1
"$DRAPE" materials >"$out" 2>"$err" && grep -q "^denim" "$out" && grep -q "^silk" "$out" || { echo "FAIL: drape materials"; cat "$out" "$err"; fail=1; }
"$DRAPE" materials --json >"$out" 2>"$err" || fail=1
python3 -c "import json; l=json.load(open('$out')); assert len(l) >= 6 and all(p['source'] for p in l), l; print('ok: drape materials ->', [p['name'] for p in l])" || fail=1

# An explicit run of more than ~a minute says so before it starts, with what sets the stability bound and the implicit
# solver as the way out (a sweep found silk at damping 0.1 s asking 39 million substeps for 1 s, silently). The run is
# stopped once the warning is there.
long_run_warned() { # long_run_warned "must appear" args...
    local want=$1
    shift
    "$DRAPE" "$@" >"$out" 2>"$err" &
    local pid=$! i
    for i in $(seq 1 1200); do
        grep -qF "this run takes" "$err" && break
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    kill "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
    if grep -qF "drape run: warning: this run takes" "$err" && grep -qF -- "$want" "$err" &&
        grep -qF "The implicit solver (--solver implicit) takes steps of up to 0.1 s" "$err"; then
        echo "ok: drape $* -> $(head -1 "$err")"
    else
        echo "FAIL: drape $* -> expected the long-run warning with '$want':"
        cat "$err"
        fail=1
    fi
}
cat >"$tmpdir/silk_damped.json" <<'JSON'
{"cloth": {"type": "grid", "n": 32, "size": 1.0}, "material": {"fabric": "silk", "damping": 0.1}}
JSON
long_run_warned "the damping sets that bound" run --scene "$tmpdir/silk_damped.json" --sim-seconds 1
long_run_warned "the stiffest spring" run --scene hang --size 200 --sim-seconds 60
"$DRAPE" run --scene "$tmpdir/silk_damped.json" --steps 100 >"$out" 2>"$err" && ! grep -q "this run takes" "$err" &&
    echo "ok: a short run of the same cloth has no long-run warning" ||
    { echo "FAIL: short run warned or failed"; cat "$err"; fail=1; }

# Implicit steps far from converged that leave the cloth strained get a warning naming the residual and what to change
# (a flag at 2 sweeps per 0.1 s step ends 720 % stretched), and --json says so; the scene's own implicit run does not.
expect_warning() { # expect_warning "must appear" "must not appear" args...: exit 0, one warning line
    local want=$1 not=$2
    shift 2
    timeout 60 "$DRAPE" "$@" >"$out" 2>"$err"
    local code=$?
    if [ "$code" = 0 ] && [ "$(wc -l <"$err")" = 1 ] && grep -qF "far from converged (relative residual" "$err" &&
        grep -qF -- "$want" "$err" && ! grep -qF -- "$not" "$err"; then
        echo "ok: drape $* -> $(cat "$err")"
    else
        echo "FAIL: drape $* -> exit $code, expected exit 0 and one warning line with '$want' and without '$not':"
        cat "$err"
        fail=1
    fi
}
# The strain limit not honoured at 1 sweep per 0.1 s step: the advice names the sweeps, not the stiffness (an
# adversarial sweep, 2026-12-01). 30 steps: in 10 the strain retry's sub-steps (docs/implicit.md) still held the bag
# at 0.108; by 30 it is at 0.145.
expect_warning "raise --iterations (now 1, allowed [1, 1000]) or shorten --dt" "lower the stiffness" \
    run --scene "$repo/scenes/examples/bag.json" --solver implicit --iterations 1 --dt 0.1 --steps 30
expect_warning "raise --iterations (now 2, allowed [1, 1000])" "--tolerance" \
    run --scene flag --solver implicit --iterations 2 --dt 0.1 --sim-seconds 2
# A tolerance that stops the sweeps early is what to change, not the iterations already at their maximum.
expect_warning "lower --tolerance (now 0.2) below 0.1" "raise --iterations" \
    run --scene flag --solver implicit --iterations 1000 --tolerance 0.2 --sim-seconds 0.3
"$DRAPE" run --scene flag --solver implicit --iterations 2 --dt 0.1 --sim-seconds 2 --json >"$out" 2>/dev/null
python3 -c "import json; j=json.load(open('$out')); assert j['implicit']['unconverged'] is True, j['implicit']; print('ok: --json implicit.unconverged true')" || fail=1
"$DRAPE" run --scene flag --solver implicit --sim-seconds 2 --json >"$out" 2>"$err"
if [ $? = 0 ] && [ ! -s "$err" ] &&
    python3 -c "import json; j=json.load(open('$out')); assert j['implicit']['unconverged'] is False, j['implicit']"; then
    echo "ok: converged implicit flag -> no warning, implicit.unconverged false"
else
    echo "FAIL: implicit flag at its default sweeps warned:"; cat "$err"; fail=1
fi

for h in "--help" "run --help"; do
    # shellcheck disable=SC2086
    if ! "$DRAPE" $h >"$out" 2>&1 || ! grep -q -- "--" "$out"; then echo "FAIL: drape $h"; fail=1; fi
done
grep -q -- "--integrator" <("$DRAPE" run --help) || { echo "FAIL: run --help lacks --integrator"; fail=1; }

if [ $fail = 0 ]; then
    echo "cli contract: all checks passed"
else
    sleep 0.2 # let tee catch up
    echo "== cli contract: the failed checks again (with what they printed) =="
    grep -A8 -E "^FAIL|Traceback|Error" "$log" | grep -v "^ok: "
fi
exit $fail

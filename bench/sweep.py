#!/usr/bin/python3
"""Runs drape's Google Benchmark binary (or reads its JSON) and writes the figures of BENCH.md into an output
directory: build/bench by default, so that a trial run never overwrites the committed figures; `--out docs/bench`
refreshes those explicitly.

  hang.json        raw Google Benchmark JSON of the run (not written with --from-json)
  hang.csv         one row per benchmark: name, kind, stage, N, particles, threads, particle_substeps_per_second,
                   real_time, label (+ time_unit, repetitions, statistic)
  throughput.png   figure 1: particle-substeps/s against N, one line per thread count (BM_Substep)
  scaling.png      figure 2: speed-up at T threads over 1 thread against T, one line per N (BM_Substep)
  table.md         Markdown table (N, particles, threads, throughput, scaling), also printed on stdout

Examples:
  bench/sweep.py                                      # full sweep with build/release/drape_bench -> build/bench
  bench/sweep.py --repetitions 3 --out docs/bench     # the committed figures (a few minutes)
  bench/sweep.py --bench build/tools-release/drape_bench --filter 'BM_Substep/N:(32|100)/'
  bench/sweep.py --repetitions 3                      # medians of 3 runs per benchmark
  bench/sweep.py --from-json docs/bench/hang.json --out docs/bench   # redraw from an earlier run, no benchmarking

Uses Debian's python3 with python3-matplotlib (scripts/setup.sh installs it); plots use the Agg backend (no display).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_BENCH = ROOT / "build" / "release" / "drape_bench"
DEFAULT_OUT = ROOT / "build" / "bench"
STAGE_NAMES = {0: "external_forces", 1: "spring_forces", 2: "integrate"}
CSV_FIELDS = ["name", "kind", "stage", "N", "particles", "threads", "particle_substeps_per_second", "real_time",
              "label", "time_unit", "repetitions", "statistic"]


def fail(message: str, code: int = 1) -> None:
    print(f"sweep.py: error: {message}", file=sys.stderr)
    sys.exit(code)


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bench", default=os.environ.get("DRAPE_BENCH", str(DEFAULT_BENCH)),
                   help="benchmark binary (default: build/release/drape_bench, or $DRAPE_BENCH)")
    p.add_argument("--from-json", metavar="FILE", help="read this Google Benchmark JSON instead of running")
    p.add_argument("--filter", help="passed as --benchmark_filter (a regular expression over benchmark names)")
    p.add_argument("--repetitions", type=int, help="passed as --benchmark_repetitions; medians are reported")
    p.add_argument("--out", "--out-dir", dest="out_dir", default=str(DEFAULT_OUT),
                   help="output directory (default: build/bench; the committed figures: --out docs/bench)")
    p.add_argument("bench_args", nargs="*", help="after --: further arguments for the benchmark binary")
    args = p.parse_args(argv)
    if args.repetitions is not None and args.repetitions < 1:
        p.error("--repetitions must be at least 1")
    return args


# --------------------------------------------------------------------------------------------------------------------
# Running / reading


def run_benchmark(args: argparse.Namespace, out_dir: Path) -> tuple[dict, Path]:
    bench = Path(args.bench)
    if not bench.is_file() or not os.access(bench, os.X_OK):
        fail(f"benchmark binary {bench} not found (or not executable). Build it first:\n"
             f"    cmake --preset release && cmake --build build/release --target drape_bench -j1\n"
             f"or point --bench (or $DRAPE_BENCH) at another drape_bench, or use --from-json FILE.")
    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / "hang.json"
    with tempfile.NamedTemporaryFile(prefix="hang.", suffix=".json", dir=out_dir, delete=False) as tmp:
        tmp_path = Path(tmp.name)
    cmd = [str(bench), "--benchmark_format=json", f"--benchmark_out={tmp_path}", "--benchmark_out_format=json"]
    if args.filter:
        cmd.append(f"--benchmark_filter={args.filter}")
    if args.repetitions:
        cmd.append(f"--benchmark_repetitions={args.repetitions}")
    cmd += args.bench_args
    print("sweep.py: running " + " ".join(cmd), file=sys.stderr)
    try:
        # The console copy of the JSON (stdout) is not needed: --benchmark_out has it.
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, check=False)
    except OSError as e:
        tmp_path.unlink(missing_ok=True)
        fail(f"cannot run {bench}: {e}")
    if proc.returncode != 0:
        tmp_path.unlink(missing_ok=True)
        fail(f"{bench} exited with status {proc.returncode}")
    data = load_json(tmp_path)
    tmp_path.chmod(0o644)  # NamedTemporaryFile creates 0600
    tmp_path.replace(json_path)
    return data, json_path


def load_json(path: Path) -> dict:
    try:
        with open(path) as f:
            data = json.load(f)
    except FileNotFoundError:
        fail(f"{path}: no such file")
    except json.JSONDecodeError as e:
        fail(f"{path}: not valid JSON ({e})")
    if not isinstance(data, dict) or "benchmarks" not in data:
        fail(f"{path}: not Google Benchmark JSON output (no 'benchmarks' list)")
    return data


# --------------------------------------------------------------------------------------------------------------------
# Rows


def parse_name(run_name: str) -> tuple[str, dict[str, str]]:
    """'BM_Stage/stage:1/N:316/threads:2/min_time:0.500/real_time' -> ('Stage', {'stage': '1', 'N': '316', ...})."""
    parts = run_name.split("/")
    family = parts[0][3:] if parts[0].startswith("BM_") else parts[0]
    fields = {}
    for part in parts[1:]:
        key, sep, value = part.partition(":")
        if sep:
            fields[key] = value
    return family, fields


def make_rows(data: dict) -> list[dict]:
    """One row per benchmark. With repetitions, the median aggregate stands for the benchmark."""
    by_run: dict[str, list[dict]] = defaultdict(list)
    order: list[str] = []
    for b in data["benchmarks"]:
        if b.get("error_occurred"):
            print(f"sweep.py: warning: {b.get('name')} failed: {b.get('error_message', '?')}", file=sys.stderr)
            continue
        run = b.get("run_name", b["name"])
        if run not in by_run:
            order.append(run)
        by_run[run].append(b)

    rows = []
    for run in order:
        entries = by_run[run]
        medians = [e for e in entries if e.get("run_type") == "aggregate" and e.get("aggregate_name") == "median"]
        iterations = [e for e in entries if e.get("run_type", "iteration") == "iteration"]
        if medians:
            b, statistic = medians[0], f"median of {len(iterations) or medians[0].get('repetitions', '?')} repetitions"
        elif iterations:
            b, statistic = iterations[-1], "single run" if len(iterations) == 1 else f"last of {len(iterations)}"
        else:
            continue
        kind, fields = parse_name(run)
        try:
            n = int(fields["N"])
        except (KeyError, ValueError):
            print(f"sweep.py: warning: skipping {run}: no N in its name", file=sys.stderr)
            continue
        # Thread count from the name: the JSON has two "threads" keys (Google Benchmark's own, always 1 here, and
        # drape's counter), and which one a JSON reader keeps is not guaranteed.
        threads = int(fields["threads"]) if "threads" in fields else int(b.get("threads", 1))
        stage = ""
        if "stage" in fields:
            stage = b.get("label") or STAGE_NAMES.get(int(fields["stage"]), fields["stage"])
        particles = int(b["particles"]) if "particles" in b else n * n  # hang: N x N particles
        rows.append({
            "name": run,
            "kind": kind,
            "stage": stage,
            "N": n,
            "particles": particles,
            "threads": threads,
            "particle_substeps_per_second": float(b["particle_substeps_per_second"]),
            "real_time": float(b["real_time"]),
            "label": b.get("label", ""),
            "time_unit": b.get("time_unit", "ns"),
            "repetitions": len(iterations) or 1,
            "statistic": statistic,
        })
    return rows


def add_scaling(rows: list[dict]) -> None:
    """scaling = throughput at T threads / throughput at 1 thread, same kind, stage and N."""
    base = {(r["kind"], r["stage"], r["N"]): r["particle_substeps_per_second"] for r in rows if r["threads"] == 1}
    for r in rows:
        b = base.get((r["kind"], r["stage"], r["N"]))
        r["scaling"] = r["particle_substeps_per_second"] / b if b else None


# --------------------------------------------------------------------------------------------------------------------
# Outputs


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_FIELDS, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        for r in rows:
            out = dict(r)
            out["particle_substeps_per_second"] = f"{r['particle_substeps_per_second']:.6g}"
            out["real_time"] = f"{r['real_time']:.6g}"
            w.writerow(out)


def fmt_rate(v: float) -> str:
    mantissa, exponent = f"{v:.2e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def markdown(rows: list[dict], context: dict, source: str) -> str:
    lines = []
    ctx = []
    if context.get("date"):
        ctx.append(f"run {context['date']}")
    if context.get("executable"):
        ctx.append(f"binary {context['executable']}")
    if context.get("num_cpus"):
        ctx.append(f"{context['num_cpus']} CPUs")
    if context.get("load_avg"):
        ctx.append("load average at start " + ", ".join(f"{x:.2f}" for x in context["load_avg"]))
    lines.append(f"Scene `hang`, source: {source}" + (f" ({'; '.join(ctx)})" if ctx else "") + ".")
    lines.append("Throughput = particle-substeps per second (BENCH.md figure 1); scaling = throughput at T threads / "
                 "at 1 thread, same N (figure 2).")
    lines.append("")
    sub = sorted((r for r in rows if r["kind"] == "Substep"), key=lambda r: (r["N"], r["threads"]))
    if sub:
        lines.append("### Full substep (BM_Substep: grid kernel, fused)")
        lines.append("")
        lines.append("| N | particles | threads | throughput (particle-substeps/s) | scaling |")
        lines.append("|---:|---:|---:|---:|---:|")
        for r in sub:
            scaling = f"{r['scaling']:.2f}" if r["scaling"] is not None else "–"
            lines.append(f"| {r['N']} | {r['particles']:,} | {r['threads']} | {fmt_rate(r['particle_substeps_per_second'])}"
                         f" | {scaling} |")
        lines.append("")
    other = sorted((r for r in rows if r["kind"] != "Substep"),
                   key=lambda r: (r["kind"], r["stage"], r["N"], r["threads"]))
    if other:
        lines.append("### Other benchmarks (CSR kernel, staged pipeline, single stages)")
        lines.append("")
        lines.append("| benchmark | stage | N | particles | threads | throughput (particle-substeps/s) | scaling |")
        lines.append("|---|---|---:|---:|---:|---:|---:|")
        for r in other:
            scaling = f"{r['scaling']:.2f}" if r["scaling"] is not None else "–"
            lines.append(f"| {r['kind']} | {r['stage'] or '–'} | {r['N']} | {r['particles']:,} | {r['threads']} | "
                         f"{fmt_rate(r['particle_substeps_per_second'])} | {scaling} |")
        lines.append("")
    stats = sorted({r["statistic"] for r in rows})
    lines.append(f"Each throughput comes from Google Benchmark's timed loop (real time): {', '.join(stats)}.")
    return "\n".join(lines) + "\n"


def plots(rows: list[dict], out_dir: Path, title_note: str) -> list[Path]:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.ticker import FixedLocator, NullLocator
    except ImportError:
        fail("matplotlib is missing: apt-get install python3-matplotlib (scripts/setup.sh installs it) and run this "
             "with Debian's /usr/bin/python3. hang.csv and table.md were written.", code=2)

    sub = [r for r in rows if r["kind"] == "Substep"]
    if not sub:
        print("sweep.py: no BM_Substep results: throughput.png and scaling.png not written", file=sys.stderr)
        return []
    written = []
    sizes = sorted({r["N"] for r in sub})
    thread_counts = sorted({r["threads"] for r in sub})

    # Figure 1: throughput against N, one line per thread count.
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    for t in thread_counts:
        pts = sorted((r["N"], r["particle_substeps_per_second"]) for r in sub if r["threads"] == t)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"{t} thread{'s' if t > 1 else ''}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(FixedLocator(sizes))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xticklabels([f"{n}\n({n * n:,})" for n in sizes])
    ax.set_xlabel("N (particles)")
    ax.set_ylabel("particle-substeps / s")
    ax.set_title("drape hang: full substep throughput (BM_Substep)" + title_note, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = out_dir / "throughput.png"
    fig.savefig(path)
    plt.close(fig)
    written.append(path)

    # Figure 2: speed-up against threads, one line per N.
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=120)
    for n in sizes:
        pts = sorted((r["threads"], r["scaling"]) for r in sub if r["N"] == n and r["scaling"] is not None)
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"N = {n}")
    ax.plot(thread_counts, thread_counts, linestyle="--", color="gray", label="ideal")
    ax.xaxis.set_major_locator(FixedLocator(thread_counts))
    ax.set_xlabel("threads T")
    ax.set_ylabel("speed-up (throughput at T / at 1 thread)")
    ax.set_title("drape hang: thread scaling of the full substep (BM_Substep)" + title_note, fontsize=10)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = out_dir / "scaling.png"
    fig.savefig(path)
    plt.close(fig)
    written.append(path)
    return written


def main(argv: list[str]) -> int:
    args = parse_args(argv)
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if args.from_json:
        json_path = Path(args.from_json)
        data = load_json(json_path)
    else:
        data, json_path = run_benchmark(args, out_dir)
    rows = make_rows(data)
    if not rows:
        fail(f"{json_path}: no benchmark results (is the filter too narrow?)")
    add_scaling(rows)

    context = data.get("context", {})
    try:
        source = str(json_path.resolve().relative_to(ROOT))
    except ValueError:
        source = str(json_path)
    write_csv(rows, out_dir / "hang.csv")
    table = markdown(rows, context, f"`{source}`")
    (out_dir / "table.md").write_text(table)
    print(table, end="")
    note = f"\n{context['date'][:10]}, {context.get('num_cpus', '?')} CPUs" if context.get("date") else ""
    written = plots(rows, out_dir, note)
    outputs = ["hang.csv", "table.md"] + [p.name for p in written]
    if not args.from_json:
        outputs.insert(0, json_path.name)
    print(f"sweep.py: wrote {', '.join(outputs)} in {out_dir}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

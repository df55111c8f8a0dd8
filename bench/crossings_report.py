#!/usr/bin/env python3
"""Meshing a surface with singular curves against meshing one with nodes: the whole mesh
pipeline (marching cubes, crossings, improver) on Kummer's surface at mu = 1.5 (16 nodes) and
mu = 3 (four planes: six double lines, four triple points), 128 cells, runs alternating so both
see the same machine load. Writes the 'crossings' section of docs/benchmarks.md.

Usage: crossings_report.py BUILD_DIR [--repeat N]
"""
import argparse
import json
import pathlib
import statistics
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


def run_once(exe, mu10):
    out = subprocess.run([str(exe), f"--benchmark_filter=BM_MeshPipeline/mu10:{mu10}/",
                          "--benchmark_format=json"], check=True, capture_output=True, text=True)
    (b,) = json.loads(out.stdout)["benchmarks"]
    return b


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    exe = pathlib.Path(args.build) / "bench" / "mesh_bench"
    if not exe.exists():
        print(f"crossings_report.py: {exe} not found; build with -DZEROSET_BUILD_BENCH=ON", file=sys.stderr)
        return 2
    runs = {15: [], 30: []}
    for _ in range(args.repeat):
        for mu10 in runs:
            runs[mu10].append(run_once(exe, mu10))
    med = {k: statistics.median(b["real_time"] for b in v) for k, v in runs.items()}
    ratios = [b3["real_time"] / b15["real_time"] for b15, b3 in zip(runs[15], runs[30])]
    lines = [
        "## Singular curves against nodes", "",
        f"`python3 bench/crossings_report.py build --repeat {args.repeat}`: marching cubes, crossings "
        "and the improver at 128 cells, the two surfaces run alternately (median of "
        f"{args.repeat}).", "",
        "| Kummer | vertices | improver steps | at rest | crossings ms | median s |",
        "|---|---|---|---|---|---|",
    ]
    for mu10, label in ((15, "mu = 1.5 (16 nodes)"), (30, "mu = 3 (6 double lines, 4 triple points)")):
        b = runs[mu10][-1]
        lines.append(f"| {label} | {int(b['vertices'])} | {int(b['steps'])} | "
                     f"{'yes' if b['converged'] else 'no (step limit)'} | {b['crossings_ms']:.0f} | "
                     f"{med[mu10] / 1000:.2f} |")
    lines += ["", f"Ratio mu = 3 / mu = 1.5: median {statistics.median(ratios):.2f} "
              f"(runs {', '.join(f'{r:.2f}' for r in ratios)})."]
    text = "\n".join(lines) + "\n"
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "crossings", "-"], input=text,
                   text=True, check=True)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

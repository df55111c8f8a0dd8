#!/usr/bin/env python3
"""Meshing a surface with singular curves against meshing one with nodes: the whole mesh
pipeline (marching cubes, crossings, improver) on Kummer's surface at mu = 1.5 (16 nodes) and
mu = 3 (four planes: six double lines, four triple points), 128 cells, with the remesher (the
default improver) and with the paper's improver, runs alternating so all see the same machine
load. Writes the 'crossings' section of docs/benchmarks.md.

Usage: crossings_report.py BUILD_DIR [--repeat N]
"""
import argparse
import json
import pathlib
import statistics
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent


def run_once(exe, mu10, remesh):
    out = subprocess.run([str(exe), f"--benchmark_filter=BM_MeshPipeline/mu10:{mu10}/remesh:{remesh}/",
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
    improvers = ((1, "remesher (default)"), (0, "paper's improver"))
    runs = {(mu10, r): [] for r, _ in improvers for mu10 in (15, 30)}
    for _ in range(args.repeat):
        for key in runs:
            runs[key].append(run_once(exe, *key))
    med = {k: statistics.median(b["real_time"] for b in v) for k, v in runs.items()}
    lines = [
        "## Singular curves against nodes", "",
        f"`python3 bench/crossings_report.py build --repeat {args.repeat}`: marching cubes, crossings "
        "and the improver at 128 cells, the four runs alternating (median of "
        f"{args.repeat}).", "",
        "| improver | Kummer | vertices | steps | at rest | crossings ms | median s |",
        "|---|---|---|---|---|---|---|",
    ]
    for r, name in improvers:
        for mu10, label in ((15, "mu = 1.5 (16 nodes)"), (30, "mu = 3 (6 double lines, 4 triple points)")):
            b = runs[(mu10, r)][-1]
            lines.append(f"| {name} | {label} | {int(b['vertices'])} | {int(b['steps'])} | "
                         f"{'yes' if b['converged'] else 'no (step limit)'} | "
                         f"{b['crossings_ms']:.0f} | {med[(mu10, r)] / 1000:.2f} |")
    lines.append("")
    for r, name in improvers:
        ratios = [b3["real_time"] / b15["real_time"] for b15, b3 in zip(runs[(15, r)], runs[(30, r)])]
        lines.append(f"Ratio mu = 3 / mu = 1.5, {name}: median {statistics.median(ratios):.2f} "
                     f"(runs {', '.join(f'{q:.2f}' for q in ratios)}).")
        lines.append("")
    text = "\n".join(lines) + "\n"
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "crossings", "-"], input=text,
                   text=True, check=True)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

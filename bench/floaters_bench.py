#!/usr/bin/python3
"""Floaters on the paper's Kummer scene: steps and particle updates per second.

Runs the Google Benchmark program `floaters_bench` (built with the project) on 1 and 2
threads (OMP_NUM_THREADS, OpenMP waiting as the command line sets it): each system is seeded
and settled once (untimed, with σ̂ calibrated so that about the nominal count settles), then
step() is timed at about 500, 10,000 and 100,000 floaters, with the paper's heuristics
(curvature and singularity estimators, cosine weighting, node snapping) and with the original
Witkin-Heckbert radius rule. A particle update is one floater advanced by one step. The 1997 figure beside it: 500 floaters at 5 Hz on a 133 MHz SGI Indy, about
2,500 updates per second. Writes section "floaters" of docs/benchmarks.md.

Usage: /usr/bin/python3 bench/floaters_bench.py BUILD_DIR [--repeat N] [--min-time S]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile

from openmp_env import cli_openmp_env, describe

HERE = pathlib.Path(__file__).resolve().parent
INDY_UPDATES = 2500.0  # 500 floaters at 5 Hz (Rösch, Ruhl & Saupe 1997, §3.4)
MODES = {
    "BM_KummerStep": "paper's heuristics",
    "BM_KummerStepWitkinHeckbert": "Witkin-Heckbert",
}


def find_binary(build):
    for candidate in (build / "bench" / "floaters_bench", build / "floaters_bench"):
        if candidate.exists():
            return candidate
    sys.exit(f"floaters_bench not found in {build} (build the target floaters_bench)")


def processor():
    """The processor's model name: the absolute figures below depend on it (the build targets
    the processor it runs on)."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown processor"


def run(binary, threads, repeat, min_time):
    """Median step time (ms), floaters and updates/s per (mode, requested size)."""
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        env = cli_openmp_env(OMP_NUM_THREADS=str(threads))
        cmd = [str(binary), f"--benchmark_repetitions={repeat}",
               f"--benchmark_min_time={min_time}", "--benchmark_report_aggregates_only=true",
               f"--benchmark_out={out.name}", "--benchmark_out_format=json"]
        subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        data = json.load(open(out.name))
    results = {}
    for b in data["benchmarks"]:
        # One repetition reports plain runs; several report aggregates, of which the median.
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        mode, size = b["run_name"].split("/")[:2]
        results[(mode, int(size))] = {
            "ms": b["real_time"],
            "floaters": b["floaters"],
            "updates": b["items_per_second"],
            "steps": b["steps_per_s"],
        }
    return results


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build", type=pathlib.Path)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--min-time", type=float, default=1.0)
    args = parser.parse_args()
    binary = find_binary(args.build)
    load = os.getloadavg()[0]
    runs = {t: run(binary, t, args.repeat, args.min_time) for t in (1, 2)}

    lines = [
        "## Floaters: Kummer mu = 1.5, clip sphere R = 3",
        "",
        f"Command: `/usr/bin/python3 bench/floaters_bench.py BUILD_DIR --repeat {args.repeat}` "
        f"(`floaters_bench`, medians of {args.repeat} runs on {processor()}, 2 cores; load "
        f"average {load:.1f} when the run started, on a machine shared with other work; the "
        f"absolute figures depend on the processor; OpenMP waiting as the command line sets "
        f"it: {describe(cli_openmp_env())}). Each system is seeded and settled "
        "first, with σ̂ calibrated so that about the nominal count settles (the floaters column "
        "gives the count); then only `step()` is timed. An update is one floater advanced by one "
        "step.",
        "",
        "| floaters | radius rule | threads | ms per step | steps/s | updates/s "
        "| vs 1997 (2,500/s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for mode, label in MODES.items():
        for size in (500, 10000, 100000):
            for threads in (1, 2):
                r = runs[threads].get((mode, size))
                if r is None:
                    continue
                lines.append(
                    f"| {r['floaters']:,.0f} | {label} | {threads} | {r['ms']:.2f} "
                    f"| {r['steps']:,.0f} | {r['updates'] / 1e6:.2f} M "
                    f"| {r['updates'] / INDY_UPDATES:,.0f}× |")
    big = max(runs[t][("BM_KummerStep", 100000)]["updates"] for t in runs)
    small = max(runs[t][("BM_KummerStep", 500)]["steps"] for t in runs)
    lines += [
        "",
        f"Goals: at least 5 M updates/s at 100,000 floaters (measured: {big / 1e6:.2f} M, "
        f"{'met' if big >= 5e6 else 'not met'}), at least 1,000 steps/s at 500 floaters "
        f"(measured: {small:,.0f}, {'met' if small >= 1000 else 'not met'}). "
        "The paper reports 500 floaters at 5 Hz on a 133 MHz SGI Indy.",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "floaters", "-"], input=text,
                   text=True, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

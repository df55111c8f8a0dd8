#!/usr/bin/env python3
"""The cost of calling zeroset from Python: field evaluation of 10^6 points through
Surface.eval / Surface.grad against the same library calls in C++ (bench/field_bench), and a mesh
and a picture made from Python against the CLI doing the same work. Writes the "python" section
of docs/benchmarks.md.

Usage: python_overhead.py BUILD_DIR [--repetitions N]
(BUILD_DIR configured with ZEROSET_BUILD_BENCH=ON and ZEROSET_BUILD_PYTHON=ON)
"""
import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
# The equation of bench/field_bench.cpp, at mu = 1.5.
KUMMER = ("p = 1-z-sqrt(2)*x; q = 1-z+sqrt(2)*x; r = 1+z+sqrt(2)*y; s = 1+z-sqrt(2)*y; "
          "(3-mu)*(x^2+y^2+z^2-mu)^2 - (3*mu-1)*p*q*r*s")


def cpu_seconds():
    """CPU time of this process and of its finished children (every thread)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def medians(fn, repetitions):
    """Median wall and CPU seconds of `fn` (the machine is shared: CPU time is the steadier)."""
    wall, cpu = [], []
    for _ in range(repetitions):
        w0, c0 = time.perf_counter(), cpu_seconds()
        fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(cpu_seconds() - c0)
    return statistics.median(wall), statistics.median(cpu)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build", type=pathlib.Path)
    ap.add_argument("--repetitions", type=int, default=9)
    args = ap.parse_args()
    build = args.build.resolve()
    bench, cli = build / "bench" / "field_bench", build / "apps" / "cli" / "zeroset"
    for exe in (bench, cli):
        if not exe.exists():
            print(f"python_overhead: {exe} not found; build the project first", file=sys.stderr)
            return 2
    sys.path.insert(0, str(build / "python"))
    import numpy as np
    import zeroset

    # --- field evaluation: C++ (batches of 4,096 points, one thread) and Python (10^6 points)
    out = subprocess.run(
        [str(bench), "--benchmark_filter=BM_KummerValue(sCompiled|GradientCompiled)(Million)?$",
         f"--benchmark_repetitions={args.repetitions}", "--benchmark_format=json",
         "--benchmark_report_aggregates_only=true"],
        check=True, capture_output=True, text=True).stdout
    rows = {b["run_name"]: b["items_per_second"] / 1e6 for b in json.loads(out)["benchmarks"]
            if b.get("aggregate_name") == "median"}
    cpp_values, cpp_grad = rows["BM_KummerValuesCompiled"], rows["BM_KummerValueGradientCompiled"]
    big_values = rows["BM_KummerValuesCompiledMillion"]
    big_grad = rows["BM_KummerValueGradientCompiledMillion"]
    s = zeroset.Surface(KUMMER, clip="sphere:3", mu=1.5)
    n = 1_000_000
    pts = np.random.default_rng(5).uniform(-3, 3, (n, 3))
    rate = {}
    for name, fn, threads in [("eval", s.eval, 1), ("grad", s.grad, 1), ("eval", s.eval, 0),
                              ("grad", s.grad, 0)]:
        fn(pts, threads=threads)  # warm up
        wall, cpu = medians(lambda: fn(pts, threads=threads), 3 * args.repetitions)
        # One thread: CPU time, as field_bench counts; all cores: wall time.
        rate[name, threads] = n / (cpu if threads == 1 else wall) / 1e6

    # --- a mesh and a picture: the CLI (whole process) against the same calls from Python
    reps = max(3, args.repetitions // 2)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        env = dict(os.environ)

        def run_cli(*a):
            subprocess.run([str(cli), "--quiet", *a], check=True, env=env)

        kummer = zeroset.Surface("kummer", mu=1.5)
        work = {
            "mesh kummer mu=1.5, 128 cells, improved, OBJ": (
                lambda: run_cli("mesh", "kummer", "--param", "mu=1.5", "-r", "128", "-o", str(tmp / "c.obj")),
                lambda: kummer.mesh(resolution=128).save(tmp / "p.obj")),
            "render kummer mu=1.5, 800x800, 2x2 samples, PNG": (
                lambda: run_cli("render", "kummer", "--param", "mu=1.5", "-o", str(tmp / "c.png")),
                lambda: kummer.render().save(tmp / "p.png")),
        }
        stage = {}
        for name, (c, p) in work.items():
            c(), p()  # warm up (page cache, OpenMP threads)
            stage[name] = (medians(c, reps), medians(p, reps))
        same_obj = (tmp / "c.obj").read_bytes() == (tmp / "p.obj").read_bytes()
        same_png = (tmp / "c.png").read_bytes() == (tmp / "p.png").read_bytes()

    lines = [
        "## Python module: overhead against C++",
        "",
        "Field evaluation of the Kummer quartic (mu = 1.5, the equation of `bench/field_bench.cpp`) "
        f"at 10^6 random points in [-3, 3]^3, an (n, 3) float64 array, from Python (`Surface.eval`, "
        f"`Surface.grad`; medians of {3 * args.repetitions} calls) against the same library "
        "calls in C++ (`Evaluator::values` and `values_gradients` in `field_bench`, medians of its "
        "repetitions): over 10^6 points in one call (the same work: the points stream from memory), "
        "and over a batch of 4,096 points that stays in the cache (the library's peak). One thread "
        "on both sides, throughput from CPU time as `field_bench` counts it (the machine is "
        "shared); the last rows let Python use every core, from wall time.",
        "",
        "| call | C++ 10^6 points | C++ 4,096 points (cached) | Python 10^6 points | Python / C++ 10^6 | Python / C++ cached |",
        "|---|---|---|---|---|---|",
        f"| value, 1 thread | {big_values:.1f} | {cpp_values:.1f} | {rate['eval', 1]:.1f} | {rate['eval', 1] / big_values:.2f} | {rate['eval', 1] / cpp_values:.2f} |",
        f"| value + gradient, 1 thread | {big_grad:.1f} | {cpp_grad:.1f} | {rate['grad', 1]:.1f} | {rate['grad', 1] / big_grad:.2f} | {rate['grad', 1] / cpp_grad:.2f} |",
        f"| value, all cores | {big_values:.1f} (1 thread) | {cpp_values:.1f} (1 thread) | {rate['eval', 0]:.1f} | {rate['eval', 0] / big_values:.2f} | {rate['eval', 0] / cpp_values:.2f} |",
        f"| value + gradient, all cores | {big_grad:.1f} (1 thread) | {cpp_grad:.1f} (1 thread) | {rate['grad', 0]:.1f} | {rate['grad', 0] / big_grad:.2f} | {rate['grad', 0] / cpp_grad:.2f} |",
        "",
        "Million points per second. The goal is Python / C++ ≥ 0.8 for the same work on one thread. "
        "Against the cached batch the difference is the memory traffic of 10^6 points (24 bytes in, "
        "8 or 24 out per point) and of the new result array, which the C++ call over 10^6 points "
        "pays as well.",
        "",
        f"A mesh and a picture: the `zeroset` command (the whole process, file written; medians of {reps} "
        "runs) against the same call from Python in a running interpreter, file written; wall "
        "time and CPU time (all threads). "
        f"Same files: mesh {'yes' if same_obj else 'NO'}, picture {'yes' if same_png else 'NO'}.",
        "",
        "| work | CLI wall s | Python wall s | Python / CLI wall | CLI CPU s | Python CPU s | Python / CLI CPU |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, ((cw, cc), (pw, pc)) in stage.items():
        lines.append(f"| {name} | {cw:.3f} | {pw:.3f} | {pw / cw:.2f} | {cc:.3f} | {pc:.3f} | {pc / cc:.2f} |")
    load = os.getloadavg()[0]
    lines += ["", f"Load average when measured: {load:.1f} on {os.cpu_count()} cores (other work "
              "slows the parallel and the wall-time figures most).",
              "", "Regenerate: `/usr/bin/python3 bench/python_overhead.py BUILD_DIR`."]
    with tempfile.NamedTemporaryFile("w", suffix=".md", delete=False) as f:
        f.write("\n".join(lines) + "\n")
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "python", f.name], check=True)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

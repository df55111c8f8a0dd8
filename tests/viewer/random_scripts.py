#!/usr/bin/env python3
"""Random viewer scripts: the viewer must survive any sequence of its script commands.

For each seed, draws a script of ACTIONS commands (every command of docs/viewer.md, with
extreme values: huge, tiny, negative, NaN, malformed, unknown names, odd scene files, paths that
cannot be written), runs `zeroset view` on it in a virtual X server with Mesa's software
OpenGL, and checks that

  * the viewer exits by itself (no signal, no abort, no hang past the time limit), with exit
    code 0 or 1 (1: some command failed, as many of these must);
  * memory stays flat: the peak resident size over the last third of the run is not much
    above the peak over the first third, and the peak of the run stays bounded.

A second, shorter script per seed holds an unknown command: it must be refused before the
window opens, with exit code 2 and the line named.

Usage: random_scripts.py ZEROSET_BINARY [--seeds 1..20] [--actions 300] [--keep DIR]
Deterministic for a seed (the script's text; the timing of background jobs varies).
"""
import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

# Limits of the checks: a run may take at most this long, its resident size may grow by at
# most this factor plus this many bytes from the first third to the last, and never exceed
# the ceiling.
TIME_LIMIT_S = 300
GROWTH_FACTOR = 1.5
GROWTH_SLACK = 150e6
PEAK_CEILING = 3e9

CATALOG = ["kummer", "cone", "planes", "torus", "roman", "cayley", "clebsch", "whitney",
           "dingdong", "sphere", "nosuch", "KUMMER"]
EQUATIONS = ["x^2 + y^2 + z^2 - 1", "a*x^2 + y^2 - z^2 - b", "1/x - 1", "sqrt(x) + y^2 + z^2 - 1",
             "x - x", "0", "x/0 + y", "sqrt(-1) + x", "((((", "x^", "(x^2+y^2+z^2)^1000 - 1",
             "sin(1e308*x) + y", "exp(x*1e5) - 1", "log(x) + y^2", "x*y*z - mu",
             "(" * 3000 + "x" + ")" * 3000, "x " * 2000, "1e309 * x", "\u00e9 + x", "q@ + 1"]
NUMBERS = ["0", "-0", "1", "-1", "0.5", "2", "1e-300", "-1e-300", "1e-320", "1e100", "-1e100",
           "1e101", "1e300", "1e308", "-1e308", "1.7976931348623157e308", "1e309", "nan", "NaN",
           "inf", "-inf", "abc", "0x10", "1e", "--1", "3.14159", "100000", "-100000",
           "4294967296", "9223372036854775808", "1,5", "1_000"]
PARAMS = ["a", "b", "mu", "lambda", "t", "nosuch", "x"]
CLIPS = ["sphere:2", "sphere:1e-300@1,0,0", "sphere:1e100", "sphere:1e300", "sphere:0",
         "sphere:-1", "sphere:nan", "sphere:1@1e308,0,0", "box:1", "box:0", "box:1e308",
         "box:1,1,1,0,0,0", "box:-1,-1,-1,1,1,1", "plane:0,0,1,0.5", "plane:0,0,0,1",
         "plane:1e308,1e308,0,1", "plane:nan,0,1,0", "cylinder:1", "sphere", ":"]
FLOATER_KEYS = {
    "max_count": ["1", "50", "1000", "200000", "100000000", "100000001", "0", "-1", "nan"],
    "seed_count": ["0", "1", "5000", "100000000", "-1", "x"],
    "seed": ["0", "1", "9007199254740992", "9007199254740993", "-1", "1e3"],
    "radius": ["0", "1e-9", "0.01", "1", "1e100", "-1", "nan", "inf"],
    "radius_grading": ["0", "1", "1e100", "-1", "nan"],
    "radius_adapt": ["wh", "curvature", "singular", "mixed", "nosuch"],
    "cos_weight": ["on", "off", "maybe"], "clip_projection": ["on", "off"],
    "snap_to_nodes": ["on", "off"], "scaled_repulsion": ["on", "off"], "nosuch": ["1"],
    "feedback": ["0", "15", "1000", "1001", "-1", "nan"],
    "equilibrium_speed": ["0", "4", "1000", "1e9", "-1"],
    "estimator_interval": ["1", "8", "100000", "100001", "0", "2.5"],
}
MESH_KEYS = {
    "cells": ["1", "8", "64", "256", "1024", "32768", "32769", "0", "-5", "nan"],
    "improve": ["on", "off", "auto", "0", "10", "100000", "100001", "maybe"],
    "max_steps": ["0", "5", "100000", "100001", "-1"],
    "boundary": ["fix", "constrain", "free"], "nosuch": ["1"],
    "grid": ["auto", "dense", "sparse", "fine"], "refine_steps": ["0", "12", "64", "65", "-1"],
    "curvature": ["on", "off", "maybe"], "curvature_weight": ["0", "8", "1000", "1001", "-1"],
    "singularity": ["on", "off"], "flips": ["on", "off"], "find_singular": ["on", "off"],
    "crossings": ["on", "off"], "curves": ["on", "off", "2"],
}


def odd_scene_files(directory):
    """Scene files a hostile user might load, written once per run."""
    files = {}

    def put(name, text, mode="w"):
        path = os.path.join(directory, name)
        with open(path, mode) as f:
            f.write(text)
        files[name] = path

    put("empty.json", "")
    put("object.json", "{}")
    put("array.json", "[]")
    put("garbage.json", b"\x00\xff\xfe{\"surface\"", "wb")
    sphere = {"zeroset_scene": 1, "equation": "x^2 + y^2 + z^2 - 1", "clip": ["sphere:2"]}
    # 10^5 levels: the scene reader's depth limit refuses it with a message, before building
    # anything that deep (a recursive copy of it would overflow the stack).
    put("deep.json", json.dumps(sphere)[:-1] + ', "x": ' + "[" * 100000 + "]" * 100000 + "}")
    put("many-clips.json", json.dumps(dict(sphere, clip=["sphere:2"] * 1000000)))
    put("clips-at-limit.json", json.dumps(
        {"zeroset_scene": 1, "name": "kummer", "clip": ["sphere:%g" % (2 + k * 1e-3)
                                                        for k in range(256)]}))
    put("huge-range.json", json.dumps(dict(
        sphere, equation="a*x^2 + y^2 + z^2 - 1",
        parameters={"a": {"value": 1, "min": -1e308, "max": 1e308}})))
    put("huge-value.json", json.dumps(dict(
        sphere, equation="a*x^2 + y^2 + z^2 - 1", parameters={"a": {"value": 1e308}})))
    put("unknown.json", json.dumps(dict(sphere, zeroset_scene=99, wat={"a": [1, 2]})))
    put("big-mesh.json", json.dumps(dict(sphere, mesh={"cells": 32768})))
    files["missing.json"] = os.path.join(directory, "missing.json")
    files["directory"] = directory
    files["proc"] = "/proc/self/mem"
    return files


def draw_script(rng, actions, scenes, out_dir):
    """ACTIONS lines; every one parses (names and argument counts, and the frame-loop commands'
    numbers, are checked when the script is read: an empty argument is no argument), the
    values are extreme."""
    def num():
        return rng.choice(NUMBERS)

    def small_path(ext):
        return os.path.join(out_dir, "out%d.%s" % (rng.randrange(4), ext))

    def bad_path(ext):
        return rng.choice(["/nonexistent/dir/x." + ext, "/proc/x." + ext, out_dir,
                           os.path.join(out_dir, "noext"), "/dev/full"])

    def path(ext):
        return small_path(ext) if rng.random() < 0.6 else bad_path(ext)

    def random_setting():
        """`set OBJECT.KEY VALUE`'s arguments: mostly real keys, some of no object."""
        obj, keys = rng.choice([("floaters", FLOATER_KEYS), ("mesh", MESH_KEYS)])
        key = rng.choice(sorted(keys))
        name = rng.choice([obj + "." + key] * 8 + [key, "render." + key, obj + "."])
        return name, rng.choice(keys[key] + [num()])

    makers = [
        (6, lambda: "equation " + rng.choice(EQUATIONS)),
        (4, lambda: "catalog " + rng.choice(CATALOG)),
        (5, lambda: "load " + rng.choice(list(scenes.values()) + [small_path("json")])),
        (12, lambda: "param %s %s" % (rng.choice(PARAMS), num())),
        (6, lambda: "range %s %s %s" % (rng.choice(PARAMS), num(), num())),
        (6, lambda: "clip " + " ".join(rng.choice(CLIPS) for _ in range(rng.choice([1, 1, 2, 3, 300])))),
        (8, lambda: "mode " + rng.choice(["floaters", "mesh", "raytrace"])),
        (3, lambda: "play" + rng.choice(["", " " + rng.choice(PARAMS)])),
        (2, lambda: "pause"),
        (5, lambda: "keyframe " + rng.choice([
            "add %s%s" % (rng.choice(["0", "0.25", "0.5", "1", num()]),
                          rng.choice(["", " in", " out", " linear", " in-out", " bouncy"])),
            "update %s" % rng.choice(["0", "1", "7", "-1", num()]),
            "ease %s %s" % (rng.choice(["0", "1", "9"]), rng.choice(["in", "out", "x"])),
            "move %s %s" % (rng.choice(["0", "1", "2"]),
                            rng.choice(["0", "0.3", "0.7", "1", num()])),
            "delete %s" % rng.choice(["0", "1", "5", num()]),
            "clear", "time %s" % rng.choice(["0", "0.5", "1", num()]), "wobble"])),
        (2, lambda: "loop " + rng.choice(["on", "off", "maybe"])),
        (3, lambda: "speed " + num()),
        (8, lambda: "floaters " + " ".join(
            "%s=%s" % (k, rng.choice(v)) for k, v in rng.sample(sorted(FLOATER_KEYS.items()), 2))
            if rng.random() < 0.9 else "floaters reset"),
        (6, lambda: "mesh " + " ".join(
            "%s=%s" % (k, rng.choice(v)) for k, v in rng.sample(sorted(MESH_KEYS.items()), 2))),
        (4, lambda: "set %s %s" % random_setting()),
        (2, lambda: "draw " + rng.choice(["disks", "points", "cubes"])),
        (2, lambda: "disk-scale " + num()),
        (2, lambda: "point-size " + num()),
        (2, lambda: "wireframe " + rng.choice(["on", "off"])),
        (3, lambda: "singular " + rng.choice(["on", "off"])),
        (1, lambda: "lights " + rng.choice(["follow", "fixed", "off"])),
        (2, lambda: "color %s %s %s %s" % (rng.choice(["front", "back", "background", "x"]),
                                           num(), num(), num())),
        (4, lambda: "camera %s %s" % (num(), num()) + rng.choice(["", " " + num()])),
        (3, lambda: "orbit %s %s" % (num(), num())),
        (3, lambda: "zoom " + num()),
        (2, lambda: "pan %s %s" % (num(), num())),
        (2, lambda: "reset-view"),
        (3, lambda: "save-scene " + path("json")),
        (2, lambda: "save-mesh " + path(rng.choice(["ply", "obj", "stl", "txt"]))),
        (2, lambda: "save-floaters " + path("ply")),
        (2, lambda: "save-pov " + path("pov")),
        (10, lambda: "frames %d" % rng.choice([0, 1, 1, 2, 3, 5])),
        (2, lambda: "sleep %s" % rng.choice(["0", "0.01", "0.05", "0.1"])),
        (3, lambda: "wait %s" % rng.choice(["0", "0.05", "0.2", "0.5"])),
        (2, lambda: "steps %d %s" % (rng.choice([0, 1, 10, 1000000]), rng.choice(["0", "0.1", "0.3"]))),
        (3, lambda: "screenshot " + path("png")),
        (2, lambda: "ui " + rng.choice(["on", "off"])),
        (2, lambda: "stats"),
        (1, lambda: "expect-error" + rng.choice(["", " must"])),
    ]
    weights = [w for w, _ in makers]
    lines = []
    for _ in range(actions):
        make = rng.choices(makers, weights=weights)[0][1]
        lines.append(make())
    return "\n".join(lines) + "\n"


def zeroset_pid(parent, binary):
    """The viewer's process under xvfb-run (a descendant of `parent` running `binary`; it
    re-executes itself, so its name may be "exe"), or None."""
    try:
        out = subprocess.run(["ps", "-e", "-o", "pid=,ppid=,args="], capture_output=True,
                             text=True).stdout
    except OSError:
        return None
    children = {}
    for line in out.splitlines():
        parts = line.split(None, 2)
        if len(parts) == 3:
            children.setdefault(int(parts[1]), []).append((int(parts[0]), parts[2]))
    todo = [parent]
    while todo:
        p = todo.pop()
        for pid, args in children.get(p, []):
            if args.split(" ", 1)[0] == binary:
                return pid
            todo.append(pid)
    return None


def rss_bytes(pid):
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def run_viewer(binary, surface, script, timeout):
    """Runs the viewer on `script`; returns (exit code, output, [(t, rss)], seconds).

    The X authority file is the script's own (`-f`, beside it), so xvfb-run makes no temporary
    directory: removing that at exit sometimes failed and replaced the viewer's exit code."""
    env = dict(os.environ, LIBGL_ALWAYS_SOFTWARE="1")
    cmd = ["xvfb-run", "-a", "-f", script + ".xauth", "-s", "-screen 0 1024x768x24",
           binary, "view", surface, "--size", "640x480", "--script", script]
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    samples = []
    output = []
    reader = threading.Thread(target=lambda: output.append(proc.stdout.read()))
    reader.start()
    pid = None
    while proc.poll() is None:
        now = time.monotonic() - start
        if now > timeout:
            os.killpg(proc.pid, signal.SIGKILL)
            break
        if pid is None:
            pid = zeroset_pid(proc.pid, binary)
        if pid is not None:
            r = rss_bytes(pid)
            if r is not None:
                samples.append((now, r))
        time.sleep(0.05)
    proc.wait()
    reader.join()
    text = output[0].decode("utf-8", "replace") if output else ""
    return proc.returncode, text, samples, time.monotonic() - start


def memory_verdict(samples, seconds):
    """(ok, description) of the resident size over the run."""
    if len(samples) < 6:
        return True, "too short to sample (%d samples)" % len(samples)
    first = [r for t, r in samples if t <= seconds / 3]
    last = [r for t, r in samples if t >= 2 * seconds / 3]
    if not first or not last:
        return True, "too short to compare thirds"
    peak_first, peak_last, peak = max(first), max(last), max(r for _, r in samples)
    ok = peak_last <= GROWTH_FACTOR * peak_first + GROWTH_SLACK and peak <= PEAK_CEILING
    return ok, "peak RSS first third %.0f MB, last third %.0f MB, whole run %.0f MB" % (
        peak_first / 1e6, peak_last / 1e6, peak / 1e6)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binary")
    ap.add_argument("--seeds", default="1..20", help="A..B or a comma list")
    ap.add_argument("--actions", type=int, default=300)
    ap.add_argument("--keep", help="directory for the scripts and outputs (kept)")
    a = ap.parse_args()
    if shutil.which("xvfb-run") is None:
        print("xvfb-run not found: skipped")
        return 0
    if ".." in a.seeds:
        lo, hi = a.seeds.split("..")
        seeds = list(range(int(lo), int(hi) + 1))
    else:
        seeds = [int(s) for s in a.seeds.split(",")]
    work = a.keep or tempfile.mkdtemp(prefix="zeroset_random_scripts_")
    os.makedirs(work, exist_ok=True)
    scenes = odd_scene_files(work)
    failures = 0
    for seed in seeds:
        rng = random.Random(seed)
        out_dir = os.path.join(work, "out%d" % seed)
        os.makedirs(out_dir, exist_ok=True)
        script = os.path.join(work, "script%d.txt" % seed)
        with open(script, "w") as f:
            f.write(draw_script(rng, a.actions, scenes, out_dir))
        surface = rng.choice(["kummer", "sphere", "roman", "x^2 + y^2 - z^2 - 1"])
        code, text, samples, seconds = run_viewer(a.binary, surface, script, TIME_LIMIT_S)
        mem_ok, mem = memory_verdict(samples, seconds)
        errors = text.count(": error: ")
        crashed = code not in (0, 1) or "terminate called" in text or "Assertion" in text
        ok = not crashed and mem_ok
        print("seed %2d  %-4s exit %d  %5.1f s  %3d failed commands  %s" % (
            seed, "ok" if ok else "FAIL", code, seconds, errors, mem), flush=True)
        if not ok:
            failures += 1
            print("  script: %s\n  last output:\n%s" % (script, "\n".join(
                "    " + l for l in text.splitlines()[-15:])), flush=True)
        # An unknown command anywhere: refused before the window opens, naming its line.
        bad = os.path.join(work, "bad%d.txt" % seed)
        line = rng.randrange(1, 20)
        with open(bad, "w") as f:
            f.write("frames 1\n" * (line - 1) + rng.choice(["frobnicate 1", "param", "mode x",
                                                          "frames -1", "wait nan"]) + "\n")
        r = subprocess.run([a.binary, "view", "sphere", "--script", bad], capture_output=True,
                           text=True, timeout=60)
        if r.returncode != 2 or ("%s:%d" % (bad, line)) not in r.stderr:
            failures += 1
            print("  seed %d: the bad script was not refused at line %d: exit %d\n%s" % (
                seed, line, r.returncode, r.stderr), flush=True)
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    print("%d of %d runs failed" % (failures, len(seeds)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

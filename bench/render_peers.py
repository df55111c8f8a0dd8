#!/usr/bin/python3
"""Ray tracing the reference scenes: zeroset beside surf and POV-Ray, side by side in one run.

Every tool renders the same surfaces, clips and picture size (800×800, one ray per pixel, no
anti-aliasing) as whole processes, timed from start to exit, each several times; the table
gives medians. zeroset runs with 2 threads (`--threads 2`) and its `--stats` file also gives
the time of the ray casting alone (without start-up and picture output). surf
(`surf-alggeo-nox`, which runs three threads and keeps about 1.3 cores busy) gets a script
written here from each surface's equation and writes a PPM (it has no PNG output), so zeroset
is timed writing the same PPM, and also writing its usual PNG; POV-Ray 3.7 gets the scene
`zeroset export` writes (`polynomial ... sturm`, `clipped_by`), uses its default threads and
writes a PNG, so it is compared with zeroset's PNG run. Each tool's pictures are kept in the
output directory so they can be compared. Writes section "render" of docs/benchmarks.md.

Usage: /usr/bin/python3 bench/render_peers.py BUILD_DIR [--repeat N] [--out DIR]
"""
import argparse
import json
import os
import pathlib
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent

# name, catalog arguments, clip radius R, surf equation (surf's language: ^ powers, `poly`
# and `double` variables).
SCENES = [
    ("Kummer mu = 1.5, R = 3", ["kummer", "--param", "mu=1.5"], 3.0,
     "double mu=1.5;\npoly p=1-z-sqrt(2)*x;\npoly q=1-z+sqrt(2)*x;\n"
     "poly r=1+z+sqrt(2)*y;\npoly s=1+z-sqrt(2)*y;\n"
     "surface=(3-mu)*(x^2+y^2+z^2-mu)^2-(3*mu-1)*p*q*r*s;"),
    ("Barth sextic, R = 1.8", ["barth6"], 1.8,
     "double phi=(1+sqrt(5))/2;\n"
     "surface=4*(phi^2*x^2-y^2)*(phi^2*y^2-z^2)*(phi^2*z^2-x^2)-(1+2*phi)*(x^2+y^2+z^2-1)^2;"),
    ("cone, R = 1.5", ["cone"], 1.5, "surface=x^2+y^2-z^2;"),
    ("planes, R = 1", ["planes"], 1.0, "surface=x*y;"),
    ("Roman, R = 0.6", ["roman"], 0.6, "surface=x^2*y^2+y^2*z^2+z^2*x^2-x*y*z;"),
]


def surf_script(equation, radius, ppm):
    """surf draws world [-10, 10]: scale the surface so that its clip sphere (radius 9.5 in
    surf's units) is the scene's R; colours as zeroset's defaults (front orange, back blue)."""
    scale = radius / 9.5
    return "\n".join([
        "width=800;", "height=800;", "clip=sphere;", "radius=9.5;",
        f"scale_x={scale:.6f};", f"scale_y={scale:.6f};", f"scale_z={scale:.6f};",
        "rot_x=-1.2;", "rot_y=0.5;",
        "surface_red=230;", "surface_green=170;", "surface_blue=90;",
        "inside_red=70;", "inside_green=95;", "inside_blue=160;",
        "antialiasing=1;", equation, "draw_surface;",
        f'filename="{ppm}";', "color_file_format=ppm;", "save_color_image;", ""])


def timed(cmd, repeat, cwd=None, after_run=None):
    """Median wall time and median CPU time (user + system, all threads) of `cmd`; calls
    `after_run()` after each run."""
    wall, cpu = [], []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        r = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        wall.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        if r.returncode != 0:
            sys.exit(f"render_peers: {' '.join(map(str, cmd))} failed:\n{r.stdout.decode()}")
        if after_run:
            after_run()
    return statistics.median(wall), statistics.median(cpu)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build_dir")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", help="keep the pictures here (default: a temporary directory)")
    args = ap.parse_args()
    zeroset = pathlib.Path(args.build_dir) / "apps" / "cli" / "zeroset"
    if not zeroset.exists():
        sys.exit(f"render_peers: {zeroset} not found; build the `zeroset` target first")
    have_surf = shutil.which("surf-alggeo-nox") is not None
    have_pov = shutil.which("povray") is not None
    out = pathlib.Path(args.out or tempfile.mkdtemp(prefix="zeroset-render-peers-"))
    out.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()[0]

    rows = []
    for i, (title, spec, radius, equation) in enumerate(SCENES):
        tag = spec[0]
        stats = out / f"{tag}-zeroset.json"
        casting = []

        def z_cmd(picture):
            return [str(zeroset), "--threads", "2", "-q", "render", *spec, "--size", "800x800",
                    "--aa", "1", "-o", str(picture)]

        # The whole processes are timed without --stats: its file also holds the singular set,
        # whose search is not part of drawing the picture. The casting time comes from
        # separate runs that write it.
        t_z_ppm = timed(z_cmd(out / f"{tag}-zeroset.ppm"), args.repeat)
        t_z = timed(z_cmd(out / f"{tag}-zeroset.png"), args.repeat)
        timed(z_cmd(out / f"{tag}-zeroset.png") + ["--stats", str(stats)], args.repeat,
              after_run=lambda: casting.append(json.loads(stats.read_text())["seconds"]))
        t_cast = statistics.median(casting)
        t_surf = t_pov = None
        if have_surf:
            pic = out / f"{tag}.pic"
            pic.write_text(surf_script(equation, radius, out / f"{tag}-surf.ppm"))
            t_surf = timed(["surf-alggeo-nox", str(pic)], args.repeat)
        if have_pov:
            pov = out / f"{tag}.pov"
            subprocess.run([str(zeroset), "-q", "export", *spec, "--size", "800x800", "-o",
                            str(pov)], check=True)
            t_pov = timed(["povray", "-D", "-V", "+W800", "+H800", f"+I{pov}",
                           f"+O{out / (tag + '-povray.png')}"], args.repeat, cwd=out)
        rows.append((title, t_z_ppm, t_z, t_cast, t_surf, t_pov))
        print(f"{title}: zeroset PPM {t_z_ppm}, PNG {t_z}, surf {t_surf}, POV-Ray {t_pov} "
              "(wall, CPU seconds)", file=sys.stderr)

    def cell(t):
        return "–" if t is None else f"{t[0]:.3f} / {t[1]:.3f}"

    def ratio(t, z, i):
        return "–" if t is None else f"{t[i] / z[i]:.1f}×"

    lines = [
        "## Ray tracing (render)",
        "",
        f"800×800 pixels, one ray per pixel, whole processes (start-up and picture output "
        f"included), median of {args.repeat} runs, as wall / CPU seconds (CPU: user + system "
        f"of all threads); load average {load:.1f} when the run started (other work on the "
        f"machine slows the 2-thread zeroset more than surf, which keeps about 1.3 cores busy, "
        f"so also compare the CPU columns). zeroset: `zeroset --threads 2 render SURFACE --aa 1` "
        f"(exact polynomial ray casting), writing a PPM as surf does (surf has no PNG output) "
        f"and writing a PNG as POV-Ray does; the casting column is the median wall time of the "
        f"ray casting alone from `--stats` (no start-up, no picture output). surf: "
        f"`surf-alggeo-nox` (its own threads) with a script from the same equation; POV-Ray "
        f"3.7: the scene of `zeroset export` (`polynomial`, `sturm`, `clipped_by`), its default "
        f"threads.",
        "",
        "| scene | zeroset, PPM | zeroset, PNG | casting only | surf (PPM) | POV-Ray (PNG) "
        "| surf / zeroset, both PPM (wall, CPU) | surf / zeroset PNG (wall, CPU) "
        "| POV-Ray / zeroset, both PNG (wall, CPU) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for title, t_z_ppm, t_z, t_cast, t_surf, t_pov in rows:
        lines.append(f"| {title} | {cell(t_z_ppm)} | {cell(t_z)} | {t_cast:.3f} | {cell(t_surf)} "
                     f"| {cell(t_pov)} "
                     f"| {ratio(t_surf, t_z_ppm, 0)}, {ratio(t_surf, t_z_ppm, 1)} "
                     f"| {ratio(t_surf, t_z, 0)}, {ratio(t_surf, t_z, 1)} "
                     f"| {ratio(t_pov, t_z, 0)}, {ratio(t_pov, t_z, 1)} |")
    lines += ["", "Regenerate: `/usr/bin/python3 bench/render_peers.py BUILD_DIR` "
              "(pictures of every tool with `--out DIR`)."]
    md = out / "render.md"
    md.write_text("\n".join(lines) + "\n")
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "render", str(md)], check=True)
    print("\n".join(lines))


if __name__ == "__main__":
    main()

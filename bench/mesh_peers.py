#!/usr/bin/python3
"""Marching cubes and implicit meshing on the Kummer surface, zeroset beside its peers; and
zeroset's remesher beside CGAL's Surface_mesher on Kummer mu = 1.5 and Barth's sextic.

Runs in one go, on the same machine: numpy field sampling + VTK's vtkFlyingEdges3D and
scikit-image's marching_cubes (64^3, 128^3, 256^3 cells over [-3, 3]^3), zeroset's polygonizer
(mesh_bench, sampling and extraction reported separately), CGAL's Surface_mesher (mesh_cgal,
when built) and zeroset's improver at 128^3. Triangle quality is computed here, the same way
for every mesh, over the triangles inside the clip sphere R = 3. Writes section "mesh" of
docs/benchmarks.md; the remesher's comparison writes section "remesh" (--remesh-only runs just
that one).

Usage: /usr/bin/python3 bench/mesh_peers.py BUILD_DIR [--repeat N] [--remesh-only]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from openmp_env import cli_openmp_env, describe

MU = 1.5
R = 3.0
HERE = pathlib.Path(__file__).resolve().parent


def kummer(x, y, z):
    s2 = np.sqrt(2.0)
    p, q = 1 - z - s2 * x, 1 - z + s2 * x
    r, s = 1 + z + s2 * y, 1 + z - s2 * y
    w = x * x + y * y + z * z - MU
    return (3 - MU) * w * w - (3 * MU - 1) * p * q * r * s


def quality(verts, tris):
    """Minimum-angle figures over the triangles with all corners inside R (plus a little)."""
    inside = (np.linalg.norm(verts, axis=1) <= R + 1e-9)[tris].all(axis=1)
    t = tris[inside]
    a, b, c = verts[t[:, 0]], verts[t[:, 1]], verts[t[:, 2]]

    def angle(p, q, r):
        u, v = q - p, r - p
        return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), (u * v).sum(axis=1)))

    m = np.minimum(np.minimum(angle(a, b, c), angle(b, c, a)), angle(c, a, b))
    return {"triangles": int(len(t)), "below30": float((m < 30).mean() * 100),
            "below10": float((m < 10).mean() * 100), "mean": float(m.mean())}


def median_time(fn, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def run_peers(n, repeat):
    import vtk
    from vtk.util import numpy_support
    from skimage import measure

    h = 2 * R / n
    ax = np.linspace(-R, R, n + 1)

    def sample():
        # Broadcasting: the fastest way numpy offers (no coordinate arrays of the full grid).
        return kummer(ax[:, None, None], ax[None, :, None], ax[None, None, :])

    def sample_meshgrid():
        x, y, z = np.meshgrid(ax, ax, ax, indexing="ij")
        return kummer(x, y, z)

    t_sample, vol = median_time(sample, repeat)
    t_meshgrid, _ = median_time(sample_meshgrid, repeat)

    image = vtk.vtkImageData()
    image.SetDimensions(n + 1, n + 1, n + 1)
    image.SetSpacing(h, h, h)
    image.SetOrigin(-R, -R, -R)

    def to_vtk():
        # VTK wants x fastest: Fortran order of the (x, y, z) array.
        arr = numpy_support.numpy_to_vtk(vol.ravel(order="F"), deep=True)
        image.GetPointData().SetScalars(arr)

    t_copy, _ = median_time(to_vtk, repeat)

    def flying_edges(normals):
        # Without normals and scalars it makes what zeroset's extraction makes: points and
        # triangles (zeroset's normals come later, from ∇F, in its clean-up).
        fe = vtk.vtkFlyingEdges3D()
        fe.SetInputData(image)
        fe.SetValue(0, 0.0)
        fe.SetComputeNormals(normals)
        fe.SetComputeScalars(normals)

        def run():
            fe.Modified()
            fe.Update()
            return fe.GetOutput()
        return run

    t_vtk_defaults, _ = median_time(flying_edges(True), repeat)
    t_vtk, poly = median_time(flying_edges(False), repeat)
    verts = numpy_support.vtk_to_numpy(poly.GetPoints().GetData()).astype(float)
    cells = numpy_support.vtk_to_numpy(poly.GetPolys().GetData()).reshape(-1, 4)[:, 1:]
    q_vtk = quality(verts, cells)

    t_sk, (sv, sf, _, _) = median_time(lambda: measure.marching_cubes(vol, 0.0, spacing=(h, h, h)), repeat)
    q_sk = quality(sv - R, sf)
    return {"n": n, "numpy_sampling": t_sample, "numpy_meshgrid": t_meshgrid, "vtk_copy": t_copy, "vtk": t_vtk,
            "vtk_defaults": t_vtk_defaults, "skimage": t_sk,
            "vtk_quality": q_vtk, "vtk_vertices": int(len(verts)), "skimage_quality": q_sk}


def vtk_backend():
    import vtk
    return f"{vtk.vtkSMPTools.GetBackend()}, {vtk.vtkSMPTools.GetEstimatedNumberOfThreads()} threads"


def run_zeroset_bench(build, repeat):
    exe = pathlib.Path(build) / "bench" / "mesh_bench"
    env = cli_openmp_env()
    out = subprocess.run([str(exe), "--benchmark_filter=BM_Polygonize", "--benchmark_format=json",
                          f"--benchmark_repetitions={repeat}", "--benchmark_report_aggregates_only=true"],
                         check=True, capture_output=True, text=True, env=env).stdout
    rows = {}
    for b in json.loads(out)["benchmarks"]:
        if b.get("aggregate_name") != "median":
            continue
        name = b["run_name"]  # BM_Polygonize/cells:256/sparse:0/refine:12/polyrows:1/...
        key = tuple(int(part.split(":")[1]) for part in name.split("/")[1:5])
        rows[key] = b
    return rows


def run_cli_mesh(build, tmp, improve):
    exe = pathlib.Path(build) / "apps" / "cli" / "zeroset"
    stats = pathlib.Path(tmp) / f"kummer_{improve}.json"
    ply = pathlib.Path(tmp) / f"kummer_{improve}.ply"
    subprocess.run([str(exe), "--quiet", "mesh", "kummer", "--param", f"mu={MU}", "--resolution", "128",
                    "--improve", improve, "--improver", "paper", "--stats", str(stats), "-o", str(ply)],
                   check=True)
    return json.loads(stats.read_text())


def read_off(path):
    lines = [l for l in pathlib.Path(path).read_text().split("\n") if l.strip()]
    nv, nf, _ = map(int, lines[1].split())
    v = np.array([list(map(float, l.split())) for l in lines[2:2 + nv]])
    f = np.array([list(map(int, l.split()))[1:4] for l in lines[2 + nv:2 + nv + nf]])
    return v, f


BARTH_R = 1.8
PHI = (1 + 5 ** 0.5) / 2


def barth6(x, y, z):
    f2 = PHI * PHI
    w = x * x + y * y + z * z - 1
    return 4 * (f2 * x * x - y * y) * (f2 * y * y - z * z) * (f2 * z * z - x * x) - (1 + 2 * PHI) * w * w


def read_obj(path):
    v, f = [], []
    for line in pathlib.Path(path).read_text().splitlines():
        t = line.split()
        if t and t[0] == "v":
            v.append([float(a) for a in t[1:4]])
        elif t and t[0] == "f":
            f.append([int(a.split("/")[0]) - 1 for a in t[1:4]])
    return np.array(v), np.array(f)


def angle_figures(verts, tris, nodes):
    """Minimum angles, and triangles under 15° farther than two mean edge lengths from a node."""
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]

    def angle(p, q, r):
        u, v = q - p, r - p
        return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), (u * v).sum(axis=1)))

    m = np.minimum(np.minimum(angle(a, b, c), angle(b, c, a)), angle(c, a, b))
    edge = np.concatenate([np.linalg.norm(a - b, axis=1), np.linalg.norm(b - c, axis=1),
                           np.linalg.norm(c - a, axis=1)]).mean()
    centroid = (a + b + c) / 3
    far = np.ones(len(tris), bool)
    for p in nodes:
        far &= np.linalg.norm(centroid - p, axis=1) > 2 * edge
    node_gap = [float(np.linalg.norm(verts - p, axis=1).min() / edge) for p in nodes]
    return {"below30": float((m < 30).mean() * 100), "mean": float(m.mean()),
            "below15_far": int(((m < 15) & far).sum()), "edge": float(edge),
            "node_gap": max(node_gap) if node_gap else 0.0}


def residual(fn, verts, nodes, edge):
    """max |F|/|∇F| (central differences) over the vertices farther than two edges from a node."""
    h = 1e-6
    f = fn(verts[:, 0], verts[:, 1], verts[:, 2])
    g = np.stack([(fn(*(verts + h * e).T) - fn(*(verts - h * e).T)) / (2 * h) for e in np.eye(3)], 1)
    far = np.ones(len(verts), bool)
    for p in nodes:
        far &= np.linalg.norm(verts - p, axis=1) > 2 * edge
    return float((np.abs(f) / np.linalg.norm(g, axis=1))[far].max())


def run_remesh_large(exe, env, repeat):
    """Kummer at 180 cells (about 10^5 vertices): the remesher's seconds with the workers it
    measures for itself (the default) and with one, the two runs alternated."""
    rows = {"default (one worker or all cores, measured)": [], "one worker (--threads 1)": []}
    flags = {"default (one worker or all cores, measured)": [], "one worker (--threads 1)": ["--threads", "1"]}
    last = {}
    with tempfile.TemporaryDirectory() as tmp:
        obj, stats = pathlib.Path(tmp) / "k.obj", pathlib.Path(tmp) / "k.json"
        for _ in range(repeat):
            for label in rows:
                subprocess.run([str(exe), "--quiet", *flags[label], "mesh", "kummer", "--param", f"mu={MU}",
                                "--resolution", "180", "-o", str(obj), "--stats", str(stats)],
                               check=True, env=env)
                j = json.loads(stats.read_text())
                rows[label].append(j["improve"]["seconds"])
                last[label] = j
    lines = ["### 10^5 vertices: Kummer mu = 1.5 at 180 cells", "",
             f"Median seconds of {repeat} runs, the two settings alternated; the meshes are the same "
             "for any number of workers.", "",
             "| workers | vertices | seconds | relaxation steps | iterations |", "|---|---|---|---|---|"]
    for label, times in rows.items():
        j = last[label]
        imp = j["improve"]
        lines.append(f"| {label} | {j['quality_after']['vertices']:,} | {statistics.median(times):.2f} "
                     f"(runs {', '.join(f'{t:.2f}' for t in times)}) | {imp['relax_steps']} | {imp['iterations']} |")
    return lines


def run_remesh_comparison(build, repeat):
    exe = pathlib.Path(build) / "apps" / "cli" / "zeroset"
    cgal = pathlib.Path(build) / "bench" / "mesh_cgal"
    env = cli_openmp_env()
    load = os.getloadavg()[0]
    # CGAL's radius bound chosen for about the vertex count of zeroset's mesh at 128 cells.
    cases = [("kummer", ["--param", f"mu={MU}"], R, kummer, 0.032),
             ("barth6", [], BARTH_R, barth6, 0.019)]
    lines = ["## Remeshing: zeroset's remesher beside CGAL's Surface_mesher, 128 cells", "",
             f"Command: `/usr/bin/python3 bench/mesh_peers.py BUILD_DIR --remesh-only --repeat {repeat}` "
             f"(median seconds of {repeat} runs each; load average {load:.1f} when the run started; zeroset "
             f"with its command line's OpenMP settings: {describe(env)}, its remesher on one worker or "
             "all cores as it measures them; CGAL single-threaded, "
             "angle bound 30°, distance bound 0.01, 200 initial points). zeroset's time is the "
             "improvement alone (marching cubes and the crossings step take another 0.1–0.3 s). "
             "Angle figures computed here the same way for every mesh (zeroset's from its OBJ file); "
             "'< 15° away' counts triangles under 15° whose centroid is farther than two mean edge "
             "lengths from every node; 'node gap' is the largest distance from a node to the nearest "
             "vertex in mean edge lengths (0: every node is a vertex); the residual is max |F|/|∇F| "
             "over the vertices farther than two mean edge lengths from the nodes, from zeroset's "
             "--stats for zeroset (exact gradient) and by central differences for CGAL.", "",
             "| surface | mesher | vertices | seconds | min angle < 30° | < 15° away | mean min angle | "
             "node gap | max residual |", "|---|---|---|---|---|---|---|---|---|"]
    notes = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, params, radius, fn, cgal_radius in cases:
            nodes = None
            for improver in ("remesh", "paper"):
                obj = pathlib.Path(tmp) / f"{name}_{improver}.obj"
                stats = pathlib.Path(tmp) / f"{name}_{improver}.json"
                times = []
                for _ in range(repeat if improver == "remesh" else 1):
                    subprocess.run([str(exe), "--quiet", "mesh", name, *params, "--resolution", "128",
                                    "--improver", improver, "-o", str(obj), "--stats", str(stats)],
                                   check=True, env=env)
                    j = json.loads(stats.read_text())
                    times.append(j["improve"]["seconds"])
                nodes = [np.array(p["position"]) for p in j["singular_set"]["points"] if p["kind"] == "node"]
                v, f = read_obj(obj)
                a = angle_figures(v, f, nodes)
                q = j["quality_after"]
                lines.append(f"| {name} | zeroset --improver {improver} | {len(v):,} | {statistics.median(times):.2f} | "
                             f"{a['below30']:.2f}% | {a['below15_far']} | {a['mean']:.1f}° | "
                             f"{a['node_gap']:.3f} | {q['residual']['max']:.1e} |")
                if improver == "remesh":
                    imp = j["improve"]
                    notes.append(f"{name}: the remesher {'came to rest' if imp['converged'] else 'did NOT come to rest'} "
                                 f"after {imp['iterations']} iterations and {imp['relax_steps']} relaxation steps "
                                 f"({imp['splits']:,} splits, {imp['collapses']:,} collapses, {imp['flips']:,} flips), "
                                 f"{len(imp['singular_points_held'])} of {len(nodes)} nodes held by a vertex.")
            if cgal.exists():
                off = pathlib.Path(tmp) / f"{name}_cgal.off"
                times = []
                for _ in range(repeat):
                    res = json.loads(subprocess.run([str(cgal), str(cgal_radius), "0.01", str(off), name],
                                                    check=True, capture_output=True, text=True).stdout)
                    times.append(res["seconds"])
                v, f = read_off(off)
                a = angle_figures(v, f, nodes)
                lines.append(f"| {name} | CGAL Surface_mesher (radius {cgal_radius}) | {len(v):,} | "
                             f"{statistics.median(times):.2f} | {a['below30']:.2f}% | {a['below15_far']} | "
                             f"{a['mean']:.1f}° | {a['node_gap']:.3f} | {residual(fn, v, nodes, a['edge']):.1e} |")
            else:
                notes.append("CGAL was not found at build time: no CGAL row.")
    lines += [""] + notes
    lines += [""] + run_remesh_large(exe, env, repeat)
    lines += ["", "What limits the remesher, with figures (the relaxation steps until rest, which grow "
              "with the mesh, and on two workers the serial topology passes), and what was tried: "
              "docs/meshing.md, section \"Remesher\"."]
    text = "\n".join(lines) + "\n"
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "remesh", "-"], input=text, text=True, check=True)
    print(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--remesh-only", action="store_true")
    args = ap.parse_args()
    if args.remesh_only:
        run_remesh_comparison(args.build, args.repeat)
        return 0
    load = os.getloadavg()[0]
    zs = run_zeroset_bench(args.build, args.repeat)
    lines = ["## Meshing: marching cubes on Kummer mu = 1.5, grid over [-3, 3]^3, clip sphere R = 3", "",
             f"Command: `/usr/bin/python3 bench/mesh_peers.py BUILD_DIR --repeat {args.repeat}` "
             "(medians; zeroset from `mesh_bench`, its sampling and extraction from PolygonizeStats).", "",
             "Times in milliseconds, 2 threads for zeroset (OpenMP, waiting as its command line sets "
             f"it: {describe(cli_openmp_env())}) and for VTK (its SMP backend: {vtk_backend()}); load average "
             f"{load:.1f} when the run started. zeroset samples F through the polynomial's restriction to each grid "
             "row (Horner); its extraction includes vertex refinement on F along each edge (Newton inside an Illinois bracket, "
             "12 steps at most); the column without refinement (`--refine-steps 0`) does the same work as VTK (linear "
             "interpolation). Clean-up (cutting at the clip sphere, collapsing degenerate triangles, "
             "normals from ∇F) is zeroset's own extra work and not in the totals; VTK is timed likewise "
             "without normals and scalars (points and triangles only), and also with its defaults. Peers get their field "
             "from numpy by broadcasting over the axes (the faster of the two usual ways; the other, "
             "np.meshgrid, is in the note below).", "",
             "| cells | numpy sampling | VTK copy-in | vtkFlyingEdges3D | (with its default normals) | skimage | zeroset sampling | "
             "zeroset extraction | zeroset extraction, no refinement | zeroset clean-up | "
             "VTK / zeroset extraction (with refinement, without) | "
             "(numpy + VTK) / zeroset sampling + extraction (with refinement, without) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    quality_rows = []
    for n in (64, 128, 256):
        p = run_peers(n, args.repeat)
        z = zs[(n, 0, 12, 1)]
        z0 = zs[(n, 0, 0, 1)]
        zs_total = z["sampling_ms"] + z["extraction_ms"]
        zs_total_linear = z0["sampling_ms"] + z0["extraction_ms"]
        peer_total = 1e3 * (p["numpy_sampling"] + p["vtk"])
        lines.append(f"| {n}³ | {1e3 * p['numpy_sampling']:.1f} | {1e3 * p['vtk_copy']:.1f} | {1e3 * p['vtk']:.1f} | "
                     f"{1e3 * p['vtk_defaults']:.1f} | "
                     f"{1e3 * p['skimage']:.1f} | {z['sampling_ms']:.1f} | {z['extraction_ms']:.1f} | "
                     f"{z0['extraction_ms']:.1f} | {z['cleanup_ms']:.1f} | "
                     f"{1e3 * p['vtk'] / z['extraction_ms']:.2f}×, {1e3 * p['vtk'] / z0['extraction_ms']:.2f}× | "
                     f"{peer_total / zs_total:.1f}×, {peer_total / zs_total_linear:.1f}× |")
        quality_rows.append((n, p, z))
    lines += ["", "numpy through np.meshgrid instead of broadcasting: " + ", ".join(
        f"{1e3 * p['numpy_meshgrid']:.1f} ms at {n}³" for n, p, _ in quality_rows) + "."]
    sparse = zs.get((256, 1, 12, 1))
    if sparse:
        lines += ["", f"Sparse bricks at 256³: sampling {sparse['sampling_ms']:.1f} ms, extraction "
                      f"{sparse['extraction_ms']:.1f} ms (dense: {zs[(256, 0, 12, 1)]['sampling_ms']:.1f} + "
                      f"{zs[(256, 0, 12, 1)]['extraction_ms']:.1f} ms)."]
    nonpoly = zs.get((256, 0, 12, 0))
    if nonpoly:
        lines += [f"Sampling the same field through the compiled expression (Evaluator::values over rows) "
                  f"instead of the row polynomials: {nonpoly['sampling_ms']:.1f} ms at 256³."]
    lines += ["", "Triangle quality (triangles inside R):", "",
              "| mesh | triangles | min angle < 10° | < 30° | mean min angle |", "|---|---|---|---|---|"]
    for n, p, z in quality_rows:
        for name, q in (("VTK", p["vtk_quality"]), ("skimage", p["skimage_quality"])):
            lines.append(f"| {name} {n}³ | {q['triangles']:,} | {q['below10']:.1f}% | {q['below30']:.1f}% | {q['mean']:.1f}° |")
    with tempfile.TemporaryDirectory() as tmp:
        for improve in ("off", "auto"):
            j = run_cli_mesh(args.build, tmp, improve)
            q = j["quality_after"]
            name = "zeroset 128³, raw" if improve == "off" else "zeroset 128³, improved"
            lines.append(f"| {name} | {q['triangles']:,} | {q['percent_min_angle_below_10']:.1f}% | "
                         f"{q['percent_min_angle_below_30']:.1f}% | {q['mean_min_angle_deg']:.1f}° |")
            if improve == "auto":
                imp = j["improve"]
                dist = [s["in_mean_edge_lengths"] for s in q["singular_points"]]
                improved_note = (f"zeroset's improver at 128³: {imp['steps']} steps in {imp['seconds']:.1f} s "
                                 f"(converged: {imp['converged']}), {imp['edge_flips']} edge flips, max residual "
                                 f"|F|/|∇F| {q['residual']['max']:.1e} outside the node balls, farthest of the "
                                 f"16 nodes from a vertex {max(dist):.3f} mean edge lengths.")
        cgal = pathlib.Path(args.build) / "bench" / "mesh_cgal"
        if cgal.exists():
            off = pathlib.Path(tmp) / "cgal.off"
            res = json.loads(subprocess.run([str(cgal), "0.032", "0.01", str(off)], check=True,
                                            capture_output=True, text=True).stdout)
            v, f = read_off(off)
            q = quality(v, f)
            lines.append(f"| CGAL Surface_mesher (angle 30°, radius 0.032) | {q['triangles']:,} | "
                         f"{q['below10']:.1f}% | {q['below30']:.1f}% | {q['mean']:.1f}° |")
            cgal_note = f"CGAL took {res['seconds']:.2f} s for {res['vertices']:,} vertices."
        else:
            cgal_note = "CGAL was not found at build time: no CGAL row."
    lines += ["", improved_note, cgal_note]
    text = "\n".join(lines) + "\n"
    subprocess.run([sys.executable, str(HERE / "update_doc.py"), "mesh", "-"], input=text, text=True, check=True)
    print(text)
    run_remesh_comparison(args.build, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())

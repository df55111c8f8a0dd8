#!/usr/bin/python3
"""Marching cubes and implicit meshing on the Kummer surface, zeroset beside its peers.

Runs in one go, on the same machine: numpy field sampling + VTK's vtkFlyingEdges3D and
scikit-image's marching_cubes (64^3, 128^3, 256^3 cells over [-3, 3]^3), zeroset's polygonizer
(mesh_bench, sampling and extraction reported separately), CGAL's Surface_mesher (mesh_cgal,
when built) and zeroset's improver at 128^3. Triangle quality is computed here, the same way
for every mesh, over the triangles inside the clip sphere R = 3. Writes section "mesh" of
docs/benchmarks.md.

Usage: /usr/bin/python3 bench/mesh_peers.py BUILD_DIR [--repeat N]
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
                    "--improve", improve, "--stats", str(stats), "-o", str(ply)], check=True)
    return json.loads(stats.read_text())


def read_off(path):
    lines = [l for l in pathlib.Path(path).read_text().split("\n") if l.strip()]
    nv, nf, _ = map(int, lines[1].split())
    v = np.array([list(map(float, l.split())) for l in lines[2:2 + nv]])
    f = np.array([list(map(int, l.split()))[1:4] for l in lines[2 + nv:2 + nv + nf]])
    return v, f


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
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
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Hands a zeroset mesh to trimesh or PyVista, whichever is installed, and prints what they make
of it (watertightness, Euler characteristic, area); without either it says so and stops.

Usage: mesh_handoff.py [SURFACE [RESOLUTION]]   (default: kummer 64; PYTHONPATH=BUILD/python)
"""
import sys

import zeroset


def main() -> int:
    spec = sys.argv[1] if len(sys.argv) > 1 else "kummer"
    resolution = int(sys.argv[2]) if len(sys.argv) > 2 else 64
    s = zeroset.Surface(spec)
    V, F, stats = s.mesh(resolution=resolution)
    # The stats are `zeroset mesh --stats`: the remesher counts iterations, the paper's
    # improver steps.
    improve = stats.get("improve", {})
    rounds = improve.get("iterations", improve.get("steps", 0))
    print(f"{s.label}: {len(V)} vertices, {len(F)} triangles, improved in {rounds} "
          f"{'iterations' if 'iterations' in improve else 'steps'}")
    try:
        import trimesh
    except ImportError:
        trimesh = None
    if trimesh is not None:
        t = trimesh.Trimesh(vertices=V, faces=F, vertex_normals=s.grad(V), process=False)
        print(f"trimesh: watertight {t.is_watertight}, Euler characteristic "
              f"{t.euler_number}, area {t.area:.4f}")
        return 0
    try:
        import numpy as np
        import pyvista
    except ImportError:
        print("mesh_handoff: neither trimesh nor PyVista is installed; nothing to hand over")
        return 0
    cells = np.hstack([np.full((len(F), 1), 3), F]).astype(np.int64).ravel()
    p = pyvista.PolyData(V, cells)
    print(f"PyVista: {p.n_points} points, {p.n_cells} cells, area {p.area:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

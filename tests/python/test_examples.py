"""The Python examples run (and say so when the package they hand over to is missing)."""
import pathlib
import re
import subprocess
import sys

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"


def run(*args):
    done = subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_kummer_grid(tmp_path):
    out = run(EXAMPLES / "kummer_grid.py", tmp_path / "grid.png")
    assert ("wrote" in out and (tmp_path / "grid.png").stat().st_size > 10000) or \
        "matplotlib is not installed" in out


def test_mesh_handoff():
    out = run(EXAMPLES / "mesh_handoff.py", "kummer", "24")
    assert "vertices" in out
    # The remesher's iterations, as the stats name them (not a missing key's 0).
    assert re.search(r"improved in [1-9]\d* iterations", out), out
    assert any(w in out for w in ("trimesh:", "PyVista:", "neither trimesh nor PyVista"))

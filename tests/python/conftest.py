"""Shared fixtures of the Python module's tests: the zeroset CLI to compare with, run on the same
inputs (ctest sets ZEROSET_CLI and PYTHONPATH to the build tree)."""
import os
import pathlib
import subprocess

import pytest

import zeroset


def _cli_path():
    if os.environ.get("ZEROSET_CLI"):
        return pathlib.Path(os.environ["ZEROSET_CLI"])
    # BUILD/python/zeroset/__init__.py -> BUILD/apps/cli/zeroset
    return pathlib.Path(zeroset.__file__).resolve().parents[2] / "apps" / "cli" / "zeroset"


@pytest.fixture(scope="session")
def cli():
    exe = _cli_path()
    if not exe.exists():
        pytest.fail(f"the zeroset CLI is not at {exe}: build it or set ZEROSET_CLI")

    def run(*args):
        done = subprocess.run([str(exe), "--quiet", *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, f"zeroset {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout

    return run


def read_ppm(path):
    """An (h, w, 3) uint8 array of a binary PPM (P6, maxval 255) as the CLI writes it."""
    import numpy as np

    data = pathlib.Path(path).read_bytes()
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(data[start:pos])
    assert fields[0] == b"P6" and fields[3] == b"255"
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(data[pos + 1:], dtype=np.uint8).reshape(h, w, 3)


def read_floater_ply(path):
    """x, y, z, nx, ny, nz, radius of a binary PLY as `zeroset sample -o` writes it."""
    import numpy as np

    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    assert "binary_little_endian" in header
    names = [line.split()[-1] for line in header.splitlines() if line.startswith("property")]
    assert names == ["x", "y", "z", "nx", "ny", "nz", "radius"], names
    return np.frombuffer(data[end:], dtype="<f4").reshape(-1, 7)

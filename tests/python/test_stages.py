"""Meshes, floaters, pictures and POV-Ray scenes from Python are those of the CLI for the same
inputs, byte for byte; Jupyter pictures; Ctrl-C stops long calls."""
import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import zeroset
from conftest import read_floater_ply, read_ppm

PNG = b"\x89PNG\r\n\x1a\n"


def test_mesh_takes_the_scene_files_switches_as_the_cli(cli, tmp_path):
    # The paper's improver, whose switches these are (flips, curvature).
    scene = tmp_path / "switches.json"
    scene.write_text(json.dumps({"name": "kummer", "mesh": {
        "cells": 18, "improve": 15, "grid": "sparse", "refine_steps": 2, "flips": False,
        "curvature": False, "find_singular": False, "crossings": False, "curves": False,
        "improver": "paper"}}))
    cli("mesh", scene, "-o", tmp_path / "cli.obj")
    zeroset.Surface(scene).mesh().save(tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    # Arguments given win over the scene file, as flags do.
    cli("mesh", scene, "--grid", "dense", "-o", tmp_path / "cli2.obj")
    _, _, stats = zeroset.Surface(scene).mesh(grid="dense", flips=True)
    assert stats["polygonize"]["grid"] == "dense"
    assert stats["improve"]["improver"] == "paper" and stats["improve"]["edge_flips"] > 0
    zeroset.Surface(scene).mesh(grid="dense").save(tmp_path / "py2.obj")
    assert (tmp_path / "py2.obj").read_bytes() == (tmp_path / "cli2.obj").read_bytes()


@pytest.mark.parametrize("spec,args,kwargs", [
    ("kummer", ["--param", "mu=1.5", "-r", "28"], dict(resolution=28)),
    ("x^2 + y^2 - z^2 - 0.1", ["--clip", "sphere:1.5", "-r", "20", "--improve", "30",
                               "--boundary", "fix"],
     dict(clip="sphere:1.5", resolution=20, improve=30, boundary="fix")),
    ("kummer", ["--param", "mu=1.5", "-r", "20", "--improve", "20", "--improver", "paper",
                "--no-flips", "--curvature-weight", "3", "--grid", "dense", "--refine-steps",
                "4"],
     dict(resolution=20, improve=20, improver="paper", flips=False, curvature_weight=3,
          grid="dense", refine_steps=4)),
    ("kummer", ["--param", "mu=1.5", "-r", "24", "--improver", "paper"],
     dict(resolution=24, improver="paper")),
])
def test_mesh_equals_the_cli(cli, tmp_path, spec, args, kwargs):
    cli("mesh", spec, *args, "-o", tmp_path / "cli.obj")
    clip = kwargs.pop("clip", None)
    params = {"mu": 1.5} if spec == "kummer" else {}
    mesh = zeroset.Surface(spec, clip=clip, **params).mesh(**kwargs)
    mesh.save(tmp_path / "py.obj")
    assert (tmp_path / "py.obj").read_bytes() == (tmp_path / "cli.obj").read_bytes()
    V, F, stats = mesh
    assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.uint32 and F.shape[1] == 3
    assert F.max() < len(V)
    # The OBJ's vertices (9 significant digits) are the arrays' vertices.
    obj = [l.split() for l in (tmp_path / "cli.obj").read_text().splitlines()]
    ov = np.array([[float(t) for t in l[1:4]] for l in obj if l and l[0] == "v"])
    np.testing.assert_allclose(ov, V, rtol=1e-8, atol=1e-12)
    assert stats["polygonize"]["vertices"] > 0 and "improve" in stats
    assert stats["improve"]["improver"] == kwargs.get("improver", "remesh")


def _untimed(stats):
    """The stats without their timings (which differ from run to run)."""
    if isinstance(stats, dict):
        return {k: _untimed(v) for k, v in stats.items() if "second" not in k}
    if isinstance(stats, list):
        return [_untimed(v) for v in stats]
    return stats


@pytest.mark.parametrize("spec,args,kwargs", [
    ("kummer", ["--param", "mu=3", "-r", "24"], dict(params={"mu": 3}, resolution=24)),
    ("roman", ["-r", "20", "--improver", "paper", "--improve", "10"],
     dict(resolution=20, improver="paper", improve=10)),
    ("x^2 + y^2 - z^2", ["--clip", "sphere:1", "-r", "16", "--no-crossings"],
     dict(clip="sphere:1", resolution=16, crossings=False)),
])
def test_mesh_stats_are_the_clis_stats_file(cli, tmp_path, spec, args, kwargs):
    # One recipe, one statistics builder: Python's dictionary is `zeroset mesh --stats`.
    cli("mesh", spec, *args, "--stats", tmp_path / "cli.json")
    params = kwargs.pop("params", {})
    clip = kwargs.pop("clip", None)
    _, _, stats = zeroset.Surface(spec, clip=clip, **params).mesh(quality=True, **kwargs)
    assert _untimed(stats) == _untimed(json.loads((tmp_path / "cli.json").read_text()))


@pytest.mark.parametrize("spec,args,kwargs", [
    ("kummer", ["--param", "mu=1.5", "--max-count", "300", "--seed", "3"],
     dict(params={"mu": 1.5}, max_count=300, seed=3)),
    # The clip of the catalog's Kummer surface follows mu: it must start at the first value.
    ("kummer", ["--max-count", "200", "--animate", "mu=4.2:4.5", "--steps", "30",
                "--settle-steps", "100"],
     dict(max_count=200, animate=("mu", 4.2, 4.5), steps=30, settle_steps=100)),
])
def test_sample_stats_are_the_clis_stats_file(cli, tmp_path, spec, args, kwargs):
    cli("sample", spec, *args, "--stats", tmp_path / "cli.json", "-o", tmp_path / "cli.ply")
    params = kwargs.pop("params", {})
    f = zeroset.Surface(spec, **params).sample(quality=True, **kwargs)
    assert _untimed(f.stats) == _untimed(json.loads((tmp_path / "cli.json").read_text()))
    np.testing.assert_array_equal(f.positions.shape, (f.stats["metrics"]["count"], 3))


def test_mesh_warnings_are_python_warnings():
    with pytest.warns(RuntimeWarning, match="F is undefined .* of the clip"):
        zeroset.Surface("log(x) + y", clip="sphere:1").mesh(resolution=12)


def test_the_paper_improvers_own_settings_are_refused_with_the_remesher():
    kummer = zeroset.Surface("kummer", mu=1.5)
    for given in (dict(flips=False), dict(curvature=True), dict(curvature_weight=3),
                  dict(singularity=False)):
        with pytest.raises(ValueError, match=f"{next(iter(given))} sets the paper's improver.*"
                                             "add improver=\"paper\""):
            kummer.mesh(resolution=10, **given)
        assert kummer.mesh(resolution=10, improver="paper", improve=2, **given).stats[
            "improve"]["improver"] == "paper"


def test_mesh_files_of_every_format(tmp_path):
    mesh = zeroset.Surface("kummer", mu=1.5).mesh(resolution=16, improve=False, quality=True)
    assert mesh.stats["quality_after"]["triangles"] == len(mesh.faces)
    for ext in ("obj", "ply", "stl", "glb"):
        mesh.save(tmp_path / f"m.{ext}")
        assert (tmp_path / f"m.{ext}").stat().st_size > 1000
    back = zeroset.read_mesh(tmp_path / "m.ply", zeroset.Surface("kummer", mu=1.5))
    np.testing.assert_allclose(back.vertices, mesh.vertices, rtol=1e-6, atol=1e-6)
    with pytest.raises(ValueError, match="obj"):
        mesh.save(tmp_path / "m.xyz")
    assert not (tmp_path / "m.xyz").exists()


def test_a_mesh_is_carried_to_new_parameter_values_or_says_why_not():
    # A sphere of radius r: carried to r = 1.2 every vertex lies on the new sphere, the
    # triangles stay; Kummer crossing mu = 1 gains twelve nodes and cannot be carried.
    sphere = zeroset.Surface("x^2 + y^2 + z^2 - r^2", clip="sphere:2", r=1)
    mesh = sphere.mesh(resolution=12, improve=20)
    carried, stats = mesh.carry(zeroset.Surface("x^2 + y^2 + z^2 - r^2", clip="sphere:2", r=1.2))
    assert stats["carried"] and stats["reason"] == "", stats
    np.testing.assert_allclose(np.linalg.norm(carried.vertices, axis=1), 1.2, atol=1e-9)
    assert len(carried.faces) == len(mesh.faces)
    assert stats["flipped_triangles"] == 0
    kummer = zeroset.Surface("kummer", mu=0.9).mesh(resolution=16, improve=20)
    none, why = kummer.carry(zeroset.Surface("kummer", mu=1.1))
    assert none is None and not why["carried"]
    assert why["failure"] == "singular set" and "4 → 16" in why["reason"], why
    with pytest.raises(ValueError, match="improve_steps"):
        mesh.carry(sphere, improve_steps=-1)


def test_floaters_equal_the_cli(cli, tmp_path):
    cli("sample", "kummer", "--param", "mu=1.5", "--max-count", "400", "--steps", "60", "--seed", "7",
        "-o", tmp_path / "cli.ply", "--png", tmp_path / "cli.png")
    f = zeroset.Surface("kummer", mu=1.5).sample(max_count=400, steps=60, seed=7)
    f.save(tmp_path / "py.ply")
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    P, N, R = f
    ref = read_floater_ply(tmp_path / "cli.ply")
    assert P.shape == (len(ref), 3) and R.shape == (len(ref),)
    np.testing.assert_array_equal(P.astype(np.float32), ref[:, :3])
    np.testing.assert_array_equal(R.astype(np.float32), ref[:, 6])
    f.render().save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert f.stats["steps"] == 60


def test_floater_switches_equal_the_cli(cli, tmp_path):
    cli("sample", "cone", "--max-count", "300", "--steps", "40", "--seed", "4", "--no-clip-newton",
        "--no-average-mu", "--no-local-radius", "--no-taper", "--no-fission-offset",
        "--feedback", "20", "--equilibrium-speed", "3", "--estimator-interval", "5",
        "-o", tmp_path / "cli.ply")
    f = zeroset.Surface("cone").sample(
        max_count=300, steps=40, seed=4, clip_newton=False, average_radius_factor=False,
        local_nominal_radius=False, energy_taper=False, fission_offset=False, feedback=20,
        equilibrium_speed=3, estimator_interval=5)
    f.save(tmp_path / "py.ply")
    assert (tmp_path / "py.ply").read_bytes() == (tmp_path / "cli.ply").read_bytes()
    with pytest.raises(ValueError, match="feedback"):
        zeroset.Surface("cone").floaters(feedback=100)
    with pytest.raises(ValueError, match="estimator_interval"):
        zeroset.Surface("cone").floaters(estimator_interval=0)


def test_floaters_step_in_an_animation_loop():
    f = zeroset.Surface("kummer", mu=1.5).floaters(max_count=300, seed=3)
    f.step(30)
    assert f.steps_taken == 30 and f.count > 0
    f.step(10, params={"mu": 1.7})
    assert f.params["mu"] == pytest.approx(1.7)
    assert f.last_step["median_residual"] < f.nominal_radius
    f.set_params(mu=1.8)
    assert f.params["mu"] == 1.8 and f.surface.params["mu"] == 1.8
    with pytest.raises(ValueError, match="finite"):
        f.set_params(mu=float("nan"))
    with pytest.raises(ValueError, match="nu"):
        f.step(2, params={"nu": 1.0})
    with pytest.raises(ValueError, match="max_count"):
        zeroset.Surface("kummer").floaters(max_count=0)


def test_render_equals_the_cli(cli, tmp_path):
    args = ["--param", "mu=1.5", "--size", "160x120", "--camera", "40,25"]
    cli("render", "kummer", *args, "-o", tmp_path / "cli.png")
    cli("render", "kummer", *args, "-o", tmp_path / "cli.ppm")
    img = zeroset.Surface("kummer", mu=1.5).render(size=(160, 120), camera=(40, 25))
    assert img.shape == (120, 160, 3) and img.dtype == np.uint8
    np.testing.assert_array_equal(img, read_ppm(tmp_path / "cli.ppm"))
    img.save(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert img._repr_png_() == (tmp_path / "cli.png").read_bytes()
    np.testing.assert_array_equal(zeroset.read_image(tmp_path / "cli.png"), img)
    assert img.stats["method"] == "polynomial roots"


def test_pov_export_equals_the_cli(cli, tmp_path):
    cli("export", "kummer", "--param", "mu=1.5", "--size", "300x200", "-o", tmp_path / "cli.pov")
    s = zeroset.Surface("kummer", mu=1.5)
    s.export_pov(tmp_path / "py.pov", size=(300, 200))
    assert (tmp_path / "py.pov").read_text() == (tmp_path / "cli.pov").read_text()
    assert s.pov_scene(size=(300, 200)) == (tmp_path / "cli.pov").read_text()


def test_orthographic_render_and_export_equal_the_cli(cli, tmp_path):
    args = ["--param", "mu=1.5", "--size", "120x90", "--camera", "30,20", "--projection",
            "ortho:4.5"]
    cli("render", "kummer", *args, "-o", tmp_path / "cli.ppm")
    s = zeroset.Surface("kummer", mu=1.5)
    img = s.render(size=(120, 90), camera=(30, 20), projection="ortho:4.5")
    np.testing.assert_array_equal(img, read_ppm(tmp_path / "cli.ppm"))
    assert not np.array_equal(img, s.render(size=(120, 90), camera=(30, 20)))
    cli("export", "kummer", "--param", "mu=1.5", "--size", "120x90", "--projection", "ortho",
        "-o", tmp_path / "cli.pov")
    pov = s.pov_scene(size=(120, 90), projection="ortho")
    assert pov == (tmp_path / "cli.pov").read_text() and "orthographic" in pov
    with pytest.raises(ValueError, match="projection"):
        s.render(size=(8, 8), projection="fisheye")
    with pytest.raises(ValueError, match="HEIGHT"):
        s.render(size=(8, 8), projection="ortho:-1")
    with pytest.raises(TypeError, match="projection"):
        s.render(size=(8, 8), projection=3)
    assert s.camera["projection"] == "perspective"


def test_thread_counts_are_bounded():
    s = zeroset.Surface("sphere")
    with pytest.raises(ValueError, match="threads"):
        s.mesh(resolution=8, threads=40000)
    with pytest.raises(ValueError, match="threads"):
        s.floaters(max_count=10, threads=5000)
    with pytest.raises(ValueError, match="threads"):
        s.render(size=(8, 8), threads=1025)
    assert s.mesh(resolution=8, threads=2).faces.shape[0] > 0


def test_render_options_are_checked():
    s = zeroset.Surface("kummer", mu=1.5)
    with pytest.raises(ValueError, match="size"):
        s.render(size=(0, 10))
    with pytest.raises(ValueError, match="elevation"):
        s.render(size=(8, 8), camera=(0, 120))
    with pytest.raises(ValueError, match="camera"):
        s.render(size=(8, 8), camera=(1, 2, 3, 4))
    with pytest.raises(ValueError):
        s.render(size=(8, 8), background="#zzzzzz")
    img = s.render(size="24x16", background=(0.5, 0.5, 0.5), front="#e6a95a", aa=1)
    assert img.shape == (16, 24, 3)


def test_jupyter_pictures():
    s = zeroset.Surface("kummer", mu=1.5)
    mesh = s.mesh(resolution=12, improve=False)
    png = mesh._repr_png_()
    assert png.startswith(PNG)
    picture = mesh.render(size=(64, 48), wireframe=True)
    assert picture.shape == (48, 64, 3) and len(np.unique(picture.reshape(-1, 3), axis=0)) > 10
    assert s.render(size=(32, 32))._repr_png_().startswith(PNG)
    assert s.floaters(max_count=50)._repr_png_().startswith(PNG)


def _interrupt_after(seconds):
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.mark.parametrize("work", [
    lambda s: s.mesh(resolution=400),
    lambda s: s.render(size=(4000, 4000), aa=4),
    lambda s: s.sample(max_count=20000, steps=100000),
])
def test_ctrl_c_stops_long_calls(work):
    s = zeroset.Surface("kummer", mu=1.5)
    start = time.monotonic()
    timer = _interrupt_after(0.4)
    try:
        with pytest.raises(KeyboardInterrupt):
            work(s)
    finally:
        timer.cancel()
    assert time.monotonic() - start < 5.0
    # Nothing half done: the surface works as before.
    assert len(s.mesh(resolution=10, improve=False).faces) > 0


def test_bad_paths_raise_value_error(tmp_path):
    s = zeroset.Surface("kummer", mu=1.5)
    with pytest.raises(ValueError):
        s.render(size=(8, 8)).save(tmp_path / "no-such-dir" / "x.png")
    with pytest.raises(ValueError, match="pov"):
        s.export_pov(tmp_path / "x.txt")
    with pytest.raises(ValueError):
        zeroset.Surface(tmp_path / "missing.json")


def test_a_floater_system_stepping_in_a_thread_refuses_other_calls():
    f = zeroset.Surface("kummer", mu=1.5).floaters(max_count=3000)
    worker = threading.Thread(target=lambda: f.step(400))
    worker.start()
    time.sleep(0.1)
    busy = worker.is_alive()
    if busy:
        with pytest.raises(RuntimeError, match="busy"):
            f.positions
    worker.join()
    assert f.steps_taken == 400 and len(f.positions) == f.count

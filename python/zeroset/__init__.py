"""zeroset: make implicit surfaces F(x, y, z; q) = 0 visible, from Python.

A thin face over the zeroset C++ library: every call runs the same library functions as the
matching ``zeroset`` command, so the results are the same (docs/python.md).

    >>> import zeroset
    >>> s = zeroset.Surface("kummer", mu=1.5)
    >>> V, F, stats = s.mesh(resolution=64)
    >>> picture = s.render(size=(400, 300))        # (300, 400, 3) uint8, shows itself in Jupyter

Bad input raises ValueError (TypeError for a wrong type), other failures RuntimeError. Long
calls release the GIL and stop on Ctrl-C (KeyboardInterrupt), leaving nothing half done.
"""
import json as _json
import math as _math
import os as _os
import warnings as _warnings
from collections.abc import MutableMapping as _MutableMapping

import numpy as _np

# As the zeroset command does for its OpenMP work: workers spin briefly at a barrier, then
# sleep, so that a busy machine does not slow the parallel loops down several times. OpenMP
# reads the policy when it loads, which is with the extension below, unless the user chose one.
if "OMP_WAIT_POLICY" not in _os.environ and "GOMP_SPINCOUNT" not in _os.environ:
    _os.environ["GOMP_SPINCOUNT"] = "10000"

from . import _zeroset as _z  # noqa: E402

__all__ = ["Surface", "Mesh", "Floaters", "Image", "catalog", "read_image", "read_mesh"]


def catalog():
    """The named surfaces: a list of dicts with name, title, equation, description, params
    ({name: {value, min, max}}) and clip."""
    return _z.catalog()


def _warn(lines):
    """The library's warnings about a run (as the zeroset command prints them), as Python
    warnings."""
    for line in lines:
        _warnings.warn(line, RuntimeWarning, stacklevel=3)


# --------------------------------------------------------------------------- argument checks
def _number(value, what):
    if isinstance(value, bool) or not isinstance(value, (int, float, _np.integer, _np.floating)):
        raise TypeError(f"{what} must be a number, got {type(value).__name__}")
    value = float(value)
    if not _math.isfinite(value):
        raise ValueError(f"{what} = {value}: the value must be finite")
    return value


def _count(value, what, minimum=0):
    if isinstance(value, bool) or not isinstance(value, (int, _np.integer)):
        raise TypeError(f"{what} must be a whole number, got {type(value).__name__}")
    if value < minimum:
        raise ValueError(f"{what} = {value}: must be at least {minimum}")
    return int(value)


def _param_values(values, what="parameter"):
    if not isinstance(values, dict):
        raise TypeError(f"parameters must be a dict of name: value, got {type(values).__name__}")
    return {str(k): _number(v, f"{what} {k}") for k, v in values.items()}


def _points(points):
    """An (n, 3) C-contiguous float64 array of `points` (converted from other real dtypes)."""
    a = _np.asarray(points)
    if a.dtype.kind not in "iuf":
        raise TypeError(f"points must be an array of real numbers, got dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"points must be an (n, 3) array, got shape {a.shape}")
    return _np.ascontiguousarray(a, dtype=_np.float64)


def _numbers(value, what, lengths):
    """A list of finite numbers from a sequence or a comma-separated string."""
    if isinstance(value, str):
        parts = value.split(",")
        try:
            value = [float(p) for p in parts]
        except ValueError:
            raise ValueError(f"{what} = {value!r}: expected comma-separated numbers") from None
    try:
        items = list(value)
    except TypeError:
        raise TypeError(f"{what} must be a sequence of numbers") from None
    if len(items) not in lengths:
        raise ValueError(f"{what} = {value!r}: expected {' or '.join(map(str, lengths))} numbers")
    return [_number(v, what) for v in items]


def _size(size):
    if size is None:
        return None
    if isinstance(size, str):
        w, sep, h = size.partition("x")
        if not sep or not w.isdigit() or not h.isdigit():
            raise ValueError(f"size = {size!r}: expected WIDTHxHEIGHT, e.g. '800x600'")
        return int(w), int(h)
    try:
        w, h = size
    except (TypeError, ValueError):
        raise TypeError("size must be (width, height)") from None
    return _count(w, "size width"), _count(h, "size height")


def _color(value, what):
    if value is None or isinstance(value, str):
        return value
    return ",".join(repr(v) for v in _numbers(value, what, (3,)))


def _projection(value):
    if value is None:
        return None
    if not isinstance(value, str):
        raise TypeError("projection must be a string: 'perspective', 'ortho' or 'ortho:HEIGHT'")
    return value


def _look(size=None, aa=None, camera=None, target=None, fov=None, background=None, front=None,
          back=None, threads=0, projection=None):
    return _z._Look(
        size=_size(size), aa=None if aa is None else _count(aa, "aa"),
        camera=None if camera is None else _numbers(camera, "camera", (2, 3)),
        target=None if target is None else _numbers(target, "target", (3,)),
        fov=None if fov is None else _number(fov, "fov"),
        background=_color(background, "background"), front=_color(front, "front"),
        back=_color(back, "back"), threads=_count(threads, "threads"),
        projection=_projection(projection))


# ------------------------------------------------------------------------------------ Image
class Image(_np.ndarray):
    """An (h, w, 3) uint8 RGB picture (row 0 at the top): a numpy array that shows itself in
    Jupyter and can be saved as PNG or PPM. `stats` holds the renderer's figures, if any."""

    def __new__(cls, array, stats=None):
        a = _np.asarray(array)
        if a.ndim != 3 or a.shape[2] != 3 or a.dtype != _np.uint8:
            raise ValueError(f"an Image is an (h, w, 3) uint8 array, got {a.shape} {a.dtype}")
        obj = a.view(cls)
        obj.stats = stats
        return obj

    def __array_finalize__(self, obj):
        self.stats = getattr(obj, "stats", None)

    def _plain(self):
        return _np.ascontiguousarray(self.view(_np.ndarray))

    def save(self, path):
        """Writes the picture; the format follows the extension (.png or .ppm)."""
        _z.write_image(self._plain(), _os.fspath(path))

    def to_png(self):
        """The PNG file's bytes."""
        return _z.encode_png(self._plain())

    def _repr_png_(self):
        if self.ndim != 3 or self.shape[2] != 3 or self.dtype != _np.uint8 or self.size == 0:
            return None
        return self.to_png()


def read_image(path):
    """Reads a PNG or binary PPM into an Image."""
    return Image(_z.read_image(_os.fspath(path)))


# ------------------------------------------------------------------------------- parameters
class _Params(_MutableMapping):
    """The parameter values of a surface or a floater system, by name. Assigning a value changes
    it at once (no recompilation); names cannot be added or removed."""

    def __init__(self, get, set_):
        self._get, self._set = get, set_

    def __getitem__(self, name):
        return self._get()[name]

    def __setitem__(self, name, value):
        self._set({name: value})

    def __delitem__(self, name):
        raise TypeError("a surface's parameters cannot be removed")

    def __iter__(self):
        return iter(self._get())

    def __len__(self):
        return len(self._get())

    def update(self, other=(), **kw):
        values = dict(other, **kw)
        self._set(values)

    def __repr__(self):
        return repr(self._get())


# ----------------------------------------------------------------------------------- Surface
class Surface:
    """A surface F(x, y, z; q) = 0 inside a clip volume.

    Surface(spec, clip=None, params=None, **values): `spec` is a catalog name (see catalog()),
    an equation in the surface language ("x^2 + y^2 = z^2"), or a scene file (.json). Parameter
    values are keyword arguments (Surface("kummer", mu=1.5)) or a dict `params`; `clip` replaces
    the default clip with one spec or a list of specs, as the command line's --clip takes them
    ("sphere:3", "box:2", "plane:0,0,1,0")."""

    def __init__(self, spec, clip=None, params=None, **values):
        if isinstance(spec, _z._Surface):
            self._s = spec
            return
        if not isinstance(spec, (str, _os.PathLike)):
            raise TypeError(f"spec must be a catalog name, an equation or a scene file path, "
                            f"got {type(spec).__name__}")
        given = _param_values(dict(params or {}, **values))
        if clip is None:
            clips = []
        elif isinstance(clip, str):
            clips = [clip]
        else:
            clips = list(clip)
            if not all(isinstance(c, str) for c in clips):
                raise TypeError("clip must be a spec string or a list of them")
        self._s = _z._Surface(_os.fspath(spec), given, clips)

    # --- what it is
    name = property(lambda self: self._s.name, doc="catalog name ('' for an equation)")
    title = property(lambda self: self._s.title)
    label = property(lambda self: self._s.label, doc="the catalog name or the equation")
    equation = property(lambda self: self._s.equation, doc="the expression, definitions substituted")
    degree = property(lambda self: self._s.degree, doc="total degree, -1 when not a polynomial")
    clip = property(lambda self: self._s.clip, doc="the clip as specs")
    camera = property(lambda self: self._s.camera)

    @property
    def params(self):
        """Parameter values by name (dict-like; `s.params["mu"] = 2` changes one)."""
        return _Params(self._s.get_params, self._set_params)

    @params.setter
    def params(self, values):
        self._set_params(dict(values))

    def _set_params(self, values):
        self._s.set_params(_param_values(values))

    def copy(self):
        return Surface(self._s.copy())

    def __repr__(self):
        params = ", ".join(f"{k}={v:g}" for k, v in self._s.get_params().items())
        return f"zeroset.Surface({self.label!r}{', ' if params else ''}{params}, clip={self.clip})"

    def info(self, singular=True):
        """Degree, parameters (values and ranges), clip, the known singular points and the
        singular set found numerically (None without a bounded clip): points as an (k, 3)
        array with `point_kinds`, curves as dicts with a (m, 3) `vertices` array and a kind."""
        s = self._s
        return {
            "name": s.name, "title": s.title, "equation": s.equation, "degree": s.degree,
            "is_polynomial": s.is_polynomial, "parameters": s.get_params(),
            "ranges": s.param_ranges(), "clip": s.clip, "camera": s.camera,
            "known_singular_points": s.known_singular_points(),
            "singular_set": s.singular_set() if singular and s.bounded else None,
        }

    def singular_set(self, cells=48):
        """The singular set {F = 0, grad F = 0} found inside the (bounded) clip."""
        return self._s.singular_set(_count(cells, "cells", 2))

    # --- the field
    def _evaluate(self, fn, points, threads):
        p = _np.asarray(points)
        one = p.ndim == 1 and p.shape == (3,)
        out = fn(_points(p.reshape(1, 3) if one else p), _count(threads, "threads"))
        return out[0] if one else out

    def eval(self, points, threads=0):
        """F at each point of an (n, 3) array: an (n,) float64 array (a float for one point)."""
        return self._evaluate(self._s.eval, points, threads)

    def grad(self, points, threads=0):
        """The gradient of F at each point: (n, 3)."""
        return self._evaluate(self._s.grad, points, threads)

    def hessian(self, points, threads=0):
        """The Hessian of F at each point: (n, 3, 3)."""
        return self._evaluate(self._s.hessian, points, threads)

    # --- stages
    def mesh(self, resolution=None, improve=None, boundary=None, grid=None, refine_steps=None,
             curvature=None, curvature_weight=None, singularity=None, flips=None,
             find_singular=None, crossings=None, curves=None, improver=None, quality=False,
             threads=0):
        """Polygonizes and improves the surface as `zeroset mesh` does (its options by the same
        names, each None for the scene file's value or else the default: resolution 128;
        improve "auto", "off", True, False or a number of steps; improver "remesh" (isotropic
        remeshing) or "paper" (the spring-mass improver); boundary "constrain" or "fix"; grid
        "auto", "dense" or "sparse"; refine_steps 12; the switches True). curvature,
        curvature_weight (8, the curvature estimator's kappa_d), singularity and flips set the
        paper's improver only: given with the remesher they raise ValueError. quality=True
        adds the quality figures before and after improvement to the stats. Returns a Mesh,
        which unpacks as V, F, stats."""
        if improve is True:
            improve = "auto"
        elif improve is False:
            improve = "off"
        elif improve is not None and not isinstance(improve, str):
            improve = str(_count(improve, "improve"))
        def switch(value):
            return None if value is None else bool(value)

        if curvature_weight is not None:
            curvature_weight = float(curvature_weight)
            if not _math.isfinite(curvature_weight):
                raise ValueError(f"curvature_weight = {curvature_weight}: the value must be finite")
        m, stats, warnings = _z._mesh(
            self._s, None if resolution is None else _count(resolution, "resolution", 1), improve,
            boundary, grid, None if refine_steps is None else _count(refine_steps, "refine_steps"),
            switch(curvature), curvature_weight, switch(singularity), switch(flips),
            switch(find_singular), switch(crossings), switch(curves), improver, bool(quality),
            _count(threads, "threads"))
        _warn(warnings)
        return Mesh(m, _json.loads(stats))

    def _floater_options(self, **options):
        given = {k: v for k, v in options.items() if v is not None}
        for key, value in given.items():
            if isinstance(value, float) and not _math.isfinite(value):
                raise ValueError(f"{key} = {value}: the value must be finite")
        return _json.dumps(given)

    def floaters(self, radius=None, max_count=None, seed_count=None, seed=None, cos_weight=None,
                 clip_projection=None, snap_to_nodes=None, scaled_repulsion=None,
                 radius_grading=None, radius_adapt=None, feedback=None, equilibrium_speed=None,
                 estimator_interval=None, clip_newton=None, average_radius_factor=None,
                 local_nominal_radius=None, energy_taper=None, fission_offset=None, threads=0):
        """A floater system seeded on the surface, not yet stepped (see Floaters)."""
        opts = self._floater_options(
            radius=radius, max_count=max_count, seed_count=seed_count, seed=seed,
            cos_weight=cos_weight, clip_projection=clip_projection, snap_to_nodes=snap_to_nodes,
            scaled_repulsion=scaled_repulsion, radius_grading=radius_grading,
            radius_adapt=radius_adapt, feedback=feedback, equilibrium_speed=equilibrium_speed,
            estimator_interval=estimator_interval, clip_newton=clip_newton,
            average_radius_factor=average_radius_factor,
            local_nominal_radius=local_nominal_radius, energy_taper=energy_taper,
            fission_offset=fission_offset)
        return Floaters(_z._floaters(self._s, opts, _count(threads, "threads")))

    def sample(self, steps=None, max_steps=3000, radius=None, max_count=None, seed_count=None,
               seed=None, cos_weight=None, clip_projection=None, snap_to_nodes=None,
               scaled_repulsion=None, radius_grading=None, radius_adapt=None, feedback=None,
               equilibrium_speed=None, estimator_interval=None, clip_newton=None,
               average_radius_factor=None, local_nominal_radius=None, energy_taper=None,
               fission_offset=None, animate=None, settle_steps=1000, quality=False, threads=0):
        """Samples the surface with floaters as `zeroset sample` does: exactly `steps` steps, or
        until settled (at most max_steps). animate=("mu", 1.02, 2.44) settles at the first
        value, then moves the parameter over `steps` steps. Returns the Floaters, which unpack
        as positions, normals, radii; their `stats` say how the run went: the file
        `zeroset sample --stats` writes, with its quality figures (metrics, the coverage of the
        singular set) when quality=True. The run's warnings are RuntimeWarnings."""
        opts = self._floater_options(
            radius=radius, max_count=max_count, seed_count=seed_count, seed=seed,
            cos_weight=cos_weight, clip_projection=clip_projection, snap_to_nodes=snap_to_nodes,
            scaled_repulsion=scaled_repulsion, radius_grading=radius_grading,
            radius_adapt=radius_adapt, feedback=feedback, equilibrium_speed=equilibrium_speed,
            estimator_interval=estimator_interval, clip_newton=clip_newton,
            average_radius_factor=average_radius_factor,
            local_nominal_radius=local_nominal_radius, energy_taper=energy_taper,
            fission_offset=fission_offset)
        if animate is not None:
            try:
                name, start, end = animate
            except (TypeError, ValueError):
                raise TypeError("animate must be (name, from, to)") from None
            animate = (str(name), _number(start, "animate from"), _number(end, "animate to"))
        f, stats, warnings = _z._sample(
            self._s, opts, None if steps is None else _count(steps, "steps"),
            _count(max_steps, "max_steps"), animate, _count(settle_steps, "settle_steps"),
            bool(quality), _count(threads, "threads"))
        _warn(warnings)
        return Floaters(f, _json.loads(stats))

    def render(self, size=None, aa=None, camera=None, target=None, fov=None, background=None,
               front=None, back=None, show_singular=False, threads=0, projection=None):
        """Ray traces the surface as `zeroset render` does: size (width, height) or "WxH"
        (default 800x800 or the scene file's), aa samples per pixel side (default 2), camera
        (azimuth, elevation[, distance]) in degrees, target (x, y, z), fov in degrees, colours
        as "#rrggbb" or display (r, g, b) in [0, 1], projection "perspective", "ortho" (parallel
        rays, the window fits the clip) or "ortho:HEIGHT" (a window HEIGHT world units high).
        Returns an Image; its `stats` hold the renderer's figures."""
        look = _look(size, aa, camera, target, fov, background, front, back, threads, projection)
        rgb, stats = _z._render(self._s, look, bool(show_singular))
        return Image(rgb, stats)

    def pov_scene(self, size=None, camera=None, target=None, fov=None, background=None,
                  front=None, back=None, projection=None):
        """The POV-Ray 3.7 scene text of the view render() would draw (polynomials only)."""
        return _z._pov_scene(self._s, _look(size, None, camera, target, fov, background, front,
                                            back, projection=projection))

    def export_pov(self, path, size=None, camera=None, target=None, fov=None, background=None,
                   front=None, back=None, projection=None):
        """Writes the POV-Ray scene to `path` (.pov), as `zeroset export`."""
        _z._export_pov(self._s, _look(size, None, camera, target, fov, background, front, back,
                                      projection=projection),
                       _os.fspath(path))

    def save_scene(self, path):
        """Writes the surface as a scene file (.json) that Surface(path) and the CLI read."""
        self._s.save_scene(_os.fspath(path))

    def _repr_png_(self):
        return self.render(size=(400, 400)).to_png()


# -------------------------------------------------------------------------------------- Mesh
class Mesh:
    """A triangle mesh of a surface: `vertices` (n, 3) float64, `faces` (m, 3) uint32
    (counter-clockwise seen from the side grad F points to), `normals`, `is_boundary` (on the
    clip), `curves` (singular curves as vertex chains) and the `stats` of the run. Unpacks as
    V, F, stats; shows itself in Jupyter."""

    def __init__(self, m, stats=None):
        self._m = m
        self.stats = stats if stats is not None else {}
        self._cache = {}

    def _get(self, key):
        if key not in self._cache:
            self._cache[key] = getattr(self._m, key)
        return self._cache[key]

    vertices = property(lambda self: self._get("vertices"))
    faces = property(lambda self: self._get("faces"))
    normals = property(lambda self: self._get("normals"))
    is_boundary = property(lambda self: self._get("is_boundary"))
    curves = property(lambda self: self._get("curves"))

    def __iter__(self):
        return iter((self.vertices, self.faces, self.stats))

    def __repr__(self):
        return f"zeroset.Mesh({len(self.vertices)} vertices, {len(self.faces)} triangles)"

    def save(self, path):
        """Writes the mesh; the format follows the extension: .obj, .ply, .stl or .glb."""
        self._m.save(_os.fspath(path))

    def render(self, size=(500, 500), wireframe=False, show_singular=False, threads=0):
        """A shaded picture of the mesh, as `zeroset mesh --png` draws it."""
        w, h = _size(size)
        return Image(self._m.render(w, h, bool(wireframe), bool(show_singular),
                                    _count(threads, "threads")))

    def _repr_png_(self):
        return self.render(size=(400, 400)).to_png()

    def carry(self, surface, improve_steps=3, threads=0):
        """Carries the mesh onto `surface`, the same equation with other parameter values,
        instead of meshing it again (docs/meshing.md, "Carrying a mesh"; the viewer's live
        meshes). Returns (mesh, stats): the carried Mesh, or None where the mesh cannot follow
        (nodes appear or vanish, a sheet pinches, ...): stats["reason"] says why, and the
        surface is then meshed again with `surface.mesh()`."""
        m, stats = _z._carry(self._m, surface._s, _count(improve_steps, "improve_steps"),
                             _count(threads, "threads"))
        return (Mesh(m, stats) if m is not None else None), stats


def read_mesh(path, surface):
    """Reads a mesh file (.obj, .ply, .stl, .glb) of `surface` (used for its pictures)."""
    return Mesh(_z._read_mesh(_os.fspath(path), surface._s))


# ---------------------------------------------------------------------------------- Floaters
class Floaters:
    """Particles spread over the surface that follow it while the parameters move. Arrays of
    the state after the last step: positions (n, 3), normals (n, 3), radii (n,), ids (n,).
    Unpacks as positions, normals, radii; shows itself in Jupyter.

    An animation loop:
        f = s.sample(max_count=1000)
        for mu in numpy.linspace(1.5, 2.5, 50):
            f.step(10, params={"mu": mu})   # mu moves to its new value over 10 steps
            frames.append(f.render())
    """

    def __init__(self, f, stats=None):
        self._f = f
        self.stats = stats if stats is not None else {}

    positions = property(lambda self: self._f.positions)
    normals = property(lambda self: self._f.normals)
    radii = property(lambda self: self._f.radii)
    max_radii = property(lambda self: self._f.max_radii)
    ids = property(lambda self: self._f.ids)
    count = property(lambda self: self._f.count)
    steps_taken = property(lambda self: self._f.steps_taken)
    nominal_radius = property(lambda self: self._f.nominal_radius)
    last_step = property(lambda self: self._f.last_step, doc="figures of the last step")
    surface = property(lambda self: Surface(self._f.surface), doc="the surface as it is now")

    def __len__(self):
        return self._f.count

    def __iter__(self):
        return iter((self.positions, self.normals, self.radii))

    def __repr__(self):
        return f"zeroset.Floaters({self.count} floaters, {self.steps_taken} steps)"

    @property
    def params(self):
        """Parameter values; assigning one sets it at once (as set_params)."""
        return _Params(self._f.get_params, self.set_params)

    @params.setter
    def params(self, values):
        self.set_params(dict(values))

    def set_params(self, values=None, **kw):
        """Sets parameters at once; the floaters re-settle onto the new surface as they step."""
        self._f.set_params(_param_values(dict(values or {}, **kw)))

    def step(self, n=1, params=None):
        """Takes n steps; with `params` the parameters move linearly to those values over the n
        steps (the floaters follow the moving surface). Returns the last step's figures."""
        target = None if params is None else _param_values(dict(params))
        return self._f.step(_count(n, "n"), target)

    def reset(self, seed=None):
        """Starts again from random seeding (with another seed when given)."""
        if seed is None:
            self._f.reset()
        else:
            self._f.reseed(_count(seed, "seed"))

    def save(self, path, ascii=False):
        """Writes the floaters as PLY (x, y, z, nx, ny, nz, radius), as `zeroset sample -o`."""
        self._f.save(_os.fspath(path), bool(ascii))

    def render(self, size=(500, 500), camera=None, disk_scale=0.75, show_singular=False,
               threads=0):
        """The floaters as shaded disks, as `zeroset sample --png` draws them."""
        w, h = _size(size)
        cam = None if camera is None else _numbers(camera, "camera", (2, 3))
        return Image(self._f.render(w, h, cam, _number(disk_scale, "disk_scale"),
                                    bool(show_singular), _count(threads, "threads")))

    def _repr_png_(self):
        return self.render(size=(400, 400)).to_png()

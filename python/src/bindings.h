#pragma once
// Shared pieces of the `_zeroset` extension (docs/python.md): the surface object every call
// takes, the interruptible runner, numpy conversions. The extension has no logic of its own:
// each call does what the matching `zeroset` subcommand does, with the same library functions.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <functional>
#include <optional>
#include <span>
#include <stop_token>
#include <string>
#include <vector>

#include "zeroset/io/image.h"
#include "zeroset/surface/scene.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::python {

namespace py = pybind11;

/// A surface as resolved from a SURFACE argument (catalog name, equation or scene file) with
/// its parameter values and clip; `scene.settings` keeps the scene file's stage settings, which
/// the stages read as the command line does.
struct PySurface {
  Scene scene;
  std::string spec;  ///< what it was resolved from, for messages (as the CLI names it)
  const Surface& surface() const { return scene.surface; }
};

/// Runs `work` on a worker thread while the calling thread waits without the GIL, looking for
/// signals every 50 ms (PyErr_CheckSignals: only the main thread sees them). On a signal whose
/// handler raises (Ctrl-C: KeyboardInterrupt) it requests a stop through the token, waits for
/// the worker to return and raises that exception; whatever `work` computed is dropped, so the
/// caller must commit results only after this returns. An exception of `work` propagates.
void run_interruptible(const std::function<void(std::stop_token)>& work);

/// Points from an (n, 3) float64 C-contiguous array (already converted by the Python layer);
/// throws ValueError for another shape.
std::span<const double> points_of(const py::array_t<double, py::array::c_style>& points);
/// An (n, 3) float64 array of `points`.
py::array_t<double> to_array(std::span<const Vec3> points);
/// An (h, w, 3) uint8 array of `image`, and back (ValueError for another shape).
py::array_t<std::uint8_t> to_array(const Image& image);
Image image_of(const py::array_t<std::uint8_t, py::array::c_style>& rgb);
/// The singular set as a dict of arrays (points with kinds, curves as vertex arrays).
py::dict singular_set_dict(const SingularSet& set);

void bind_surface(py::module_& m);
void bind_mesh(py::module_& m);
void bind_floaters(py::module_& m);
void bind_render(py::module_& m);

}  // namespace zeroset::python

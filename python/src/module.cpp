// The `_zeroset` extension module: exception translation and the parts' bindings. The Python
// package zeroset (python/zeroset/__init__.py) is the interface users see.
#include "bindings.h"
#include "zeroset/error.h"

PYBIND11_MODULE(_zeroset, m) {
  namespace zp = zeroset::python;
  m.doc() = "zeroset: implicit surfaces F(x, y, z; q) = 0 (compiled part; use the zeroset package)";
  // Bad input (a parse error with its caret line, a refused option, a file that cannot be read,
  // an output path that cannot be written) is the caller's to fix: ValueError; any other
  // failure of the library (a write that failed, e.g. on a full disk: WriteError): RuntimeError.
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const zeroset::BadInput& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const zeroset::Error& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    } catch (const nlohmann::json::exception& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  zp::bind_surface(m);
  zp::bind_mesh(m);
  zp::bind_floaters(m);
  zp::bind_render(m);
}

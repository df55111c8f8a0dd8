// The interruptible runner and the numpy conversions shared by the bindings.
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include "bindings.h"
#include "zeroset/error.h"

namespace zeroset::python {

void run_interruptible(const std::function<void(std::stop_token)>& work) {
  std::stop_source source;
  std::exception_ptr error;
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  bool interrupted = false;
  std::thread worker([&, token = source.get_token()] {
    try {
      work(token);
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard lock(mutex);
    done = true;
    finished.notify_all();
  });
  {
    py::gil_scoped_release release;
    std::unique_lock lock(mutex);
    while (!finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
      lock.unlock();
      {
        py::gil_scoped_acquire acquire;
        // A handler that raised leaves its exception set here, for error_already_set below.
        interrupted = PyErr_CheckSignals() != 0;
      }
      lock.lock();
      if (interrupted) {
        source.request_stop();
        finished.wait(lock, [&] { return done; });
        break;
      }
    }
  }
  worker.join();
  if (interrupted) throw py::error_already_set();
  if (error) std::rethrow_exception(error);
}

std::span<const double> points_of(const py::array_t<double, py::array::c_style>& points) {
  if (points.ndim() != 2 || points.shape(1) != 3)
    throw py::value_error("points must be an (n, 3) array");
  return {points.data(), static_cast<size_t>(points.size())};
}

py::array_t<double> to_array(std::span<const Vec3> points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  double* d = out.mutable_data();
  for (size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = points[i][k];
  return out;
}

py::array_t<std::uint8_t> to_array(const Image& image) {
  py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(image.height),
                                 static_cast<py::ssize_t>(image.width), py::ssize_t{3}});
  std::copy(image.rgb.begin(), image.rgb.end(), out.mutable_data());
  return out;
}

Image image_of(const py::array_t<std::uint8_t, py::array::c_style>& rgb) {
  if (rgb.ndim() != 3 || rgb.shape(2) != 3 || rgb.shape(0) < 1 || rgb.shape(1) < 1)
    throw py::value_error("an image must be an (h, w, 3) uint8 array");
  Image image(static_cast<int>(rgb.shape(1)), static_cast<int>(rgb.shape(0)));
  std::copy(rgb.data(), rgb.data() + rgb.size(), image.rgb.begin());
  return image;
}

py::dict singular_set_dict(const SingularSet& set) {
  std::vector<Vec3> positions;
  py::list point_kinds, curves;
  for (const SingularPoint& p : set.points) {
    positions.push_back(p.position);
    point_kinds.append(std::string(to_string(p.kind)));
  }
  for (const SingularCurve& c : set.curves) {
    py::dict curve;
    curve["kind"] = std::string(to_string(c.kind));
    curve["closed"] = c.closed;
    curve["length"] = c.length();
    curve["vertices"] = to_array(c.points);
    curves.append(curve);
  }
  py::dict d;
  d["points"] = to_array(positions);
  d["point_kinds"] = point_kinds;
  d["curves"] = curves;
  d["has_singular_sheet"] = set.has_singular_sheet;
  const Vec3& e = set.singular_sheet_example;
  d["singular_sheet_example"] = set.has_singular_sheet
                                    ? py::object(py::make_tuple(e.x(), e.y(), e.z()))
                                    : py::object(py::none());
  d["summary"] = singular_set_summary(set);
  return d;
}

}  // namespace zeroset::python

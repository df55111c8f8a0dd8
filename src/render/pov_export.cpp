#include "zeroset/render/pov_export.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "pov_detail.h"
#include "render_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace detail {

std::string pov_number(double v) {
  if (!std::isfinite(v))
    throw BadInput(
        fmt::format("POV-Ray export: a number of the scene is not finite ({}); "
                    "POV-Ray cannot read it",
                    v));
  return fmt::format("{:.17g}", v);
}

std::string pov_vec(const Vec3& v) {
  return fmt::format("<{}, {}, {}>", pov_number(v.x()), pov_number(v.y()), pov_number(v.z()));
}

}  // namespace detail

namespace {

constexpr int kPovMaxOrder = 35;
using detail::pov_number;
using detail::pov_vec;

// A material's number, to six digits (pov_number's check).
std::string pov_short(double v) {
  (void)pov_number(v);
  return fmt::format("{:.6g}", v);
}

std::string texture(const char* keyword, const Material& m) {
  // POV-Ray: ambient × pigment + diffuse × pigment × (n·l) + phong × (r·v)^phong_size, the
  // same terms as the renderer's Phong model.
  return fmt::format(
      "  {} {{\n"
      "    pigment {{ color rgb {} }}\n"
      "    finish {{ ambient {} diffuse 1 phong {} phong_size {} }}\n"
      "  }}\n",
      keyword, pov_vec(m.diffuse), pov_short(m.ambient), pov_short(m.specular),
      pov_short(m.shininess));
}

}  // namespace

namespace detail {

Polynomial pov_polynomial(const Surface& surface) {
  const Field& field = surface.field;
  if (!field.is_polynomial())
    throw BadInput("POV-Ray export needs a polynomial surface; '" + surface.label() +
                   "' is not a polynomial in x, y, z");
  field.require_parameters();
  Polynomial poly = field.polynomial();
  if (poly.degree() > kPovMaxOrder)
    throw InvalidArgument("degree", std::to_string(poly.degree()),
                          "POV-Ray's polynomial object supports degree up to 35");
  for (const Monomial& m : poly.terms())
    if (!std::isfinite(m.c)) {
      std::string term;
      for (const auto& [name, power] :
           {std::pair{"x", m.i}, std::pair{"y", m.j}, std::pair{"z", m.k}})
        if (power > 0) term += power > 1 ? fmt::format("{}^{}", name, power) : std::string(name);
      throw BadInput(
          fmt::format("POV-Ray export: the {} of '{}' is not finite ({}); POV-Ray "
                      "cannot read it",
                      term.empty() ? std::string("constant term") : "coefficient of " + term,
                      surface.label(), m.c));
    }
  if (poly.degree() < 1)
    throw BadInput("POV-Ray export: '" + surface.label() + "' is a constant, there is no surface");
  (void)surface.bounds();  // throws BadInput when the clip is unbounded
  return poly;
}

std::string pov_preamble(const RenderOptions& options) {
  std::string out = "#version 3.7;\n";
  out += "global_settings { assumed_gamma 1.0 ambient_light rgb <1, 1, 1> }\n";
  out += fmt::format("background {{ color rgb {} }}\n\n", pov_vec(options.background));
  return out;
}

std::string pov_polynomial_object(int degree, const std::vector<PovTerm>& terms,
                                  const Surface& surface, const RenderOptions& options) {
  std::string out = fmt::format("\npolynomial {{ {},\n", degree);
  for (size_t n = 0; n < terms.size(); ++n)
    out += fmt::format("  xyz({}, {}, {}): {}{}\n", terms[n].i, terms[n].j, terms[n].k,
                       terms[n].coefficient, n + 1 < terms.size() ? "," : "");
  out += "  sturm\n  clipped_by {\n";
  for (const SphereClip& s : surface.clip.spheres)
    out += fmt::format("    sphere {{ {}, {} }}\n", pov_vec(s.center), pov_number(s.radius));
  for (const HalfSpaceClip& h : surface.clip.planes)
    out += fmt::format("    plane {{ {}, {} }}\n", pov_vec(h.normal), pov_number(h.offset));
  out += "  }\n  bounded_by { clipped_by }\n";
  out += texture("texture", options.front);
  out += texture("interior_texture", options.back);
  out += "}\n";
  return out;
}

}  // namespace detail

std::string pov_scene(const Surface& surface, const RenderOptions& options) {
  detail::validate(options);
  const Polynomial poly = detail::pov_polynomial(surface);
  const View view = View::from_camera(detail::camera_of(surface, options), surface.scene_radius(),
                                      options.width, options.height);
  const detail::Shader shader(options, view);

  std::string out;
  out += fmt::format("// {} — exported by zeroset\n", surface.label());
  out += fmt::format("// F = {}\n", poly.to_string());
  out += fmt::format("// Render: povray +W{} +H{} +Iscene.pov +Oscene.png\n", options.width,
                     options.height);
  out += detail::pov_preamble(options);
  // POV-Ray's camera is left-handed: a negative `right` makes the frame right-handed, as
  // ours. `angle` is the horizontal field of view; `sky` is the image's up direction.
  const double horizontal_deg =
      2.0 * std::atan(view.tan_half_fov * view.aspect()) * 180.0 / std::numbers::pi;
  if (view.orthographic) {
    // Parallel rays: `up` and `right` are the window's size in world units, and no `angle`.
    const double h = 2.0 * view.half_height;
    out += "camera {\n  orthographic\n";
    out += fmt::format("  location {}\n", pov_vec(view.eye));
    out += fmt::format("  sky {}\n", pov_vec(view.up));
    out += fmt::format("  up <0, {}, 0>\n", pov_number(h));
    out += fmt::format("  right <{}, 0, 0>\n", pov_number(-h * view.aspect()));
  } else {
    out += "camera {\n  perspective\n";
    out += fmt::format("  location {}\n", pov_vec(view.eye));
    out += fmt::format("  sky {}\n", pov_vec(view.up));
    out += "  up <0, 1, 0>\n";
    out += fmt::format("  right <{}, 0, 0>\n", pov_number(-view.aspect()));
    out += fmt::format("  angle {}\n", pov_number(horizontal_deg));
  }
  out += fmt::format("  look_at {}\n}}\n\n", pov_vec(view.target));
  const double far = 1000.0 * surface.scene_radius();
  for (const auto& l : shader.lights)
    out += fmt::format("light_source {{ {} color rgb {} parallel point_at {} shadowless }}\n",
                       pov_vec(view.target + far * l.direction), pov_vec(l.color),
                       pov_vec(view.target));

  std::vector<detail::PovTerm> terms;
  for (const Monomial& m : poly.terms()) terms.push_back({m.i, m.j, m.k, pov_number(m.c)});
  out += detail::pov_polynomial_object(poly.degree(), terms, surface, options);
  return out;
}

void write_pov_scene(const Surface& surface, const RenderOptions& options,
                     const std::string& path) {
  const std::string text = pov_scene(surface, options);
  write_file_atomically(path, [&](std::ostream& o) { o << text; });
}

}  // namespace zeroset

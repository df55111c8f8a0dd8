// Keyframed animations for POV-Ray: a clock-driven scene and the .ini that renders its frames.
#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <tuple>

#include "pov_detail.h"
#include "render_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/render/lights.h"
#include "zeroset/render/pov_export.h"

namespace zeroset {
namespace {

using detail::pov_vec;

/// The highest degree in the animated parameters that the coefficients' fit tries.
constexpr int kMaxParamDegree = 8;

std::string num(double v) { return detail::pov_number(v); }

/// An ease of `s` (POV-Ray text in [0, 1]) as POV-Ray text: the formulas of ease().
std::string pov_ease(Ease e, const std::string& s) {
  switch (e) {
    case Ease::kLinear:
      return s;
    case Ease::kIn:
      return fmt::format("({0} * {0})", s);
    case Ease::kOut:
      return fmt::format("(1 - (1 - {0}) * (1 - {0}))", s);
    case Ease::kInOut:
      return fmt::format("({0} * {0} * (3 - 2 * {0}))", s);
  }
  return s;
}

/// `#declare var = ...` as KeyTrack::value computes it, over clock.
std::string pov_track(const KeyTrack& t, const std::string& var) {
  const size_t n = t.times.size();
  if (n == 1) return fmt::format("#declare {} = {};\n", var, num(t.values[0]));
  std::string out = fmt::format("#if (clock <= {})\n  #declare {} = {};\n", num(t.times[0]), var,
                                num(t.values[0]));
  for (size_t i = 0; i + 1 < n; ++i) {
    const std::string s =
        fmt::format("((clock - {}) / {})", num(t.times[i]), num(t.times[i + 1] - t.times[i]));
    out += fmt::format("#elseif (clock <= {})\n  #declare {} = {} + {} * {};\n",
                       num(t.times[i + 1]), var, num(t.values[i]), pov_ease(t.eases[i], s),
                       num(t.values[i + 1] - t.values[i]));
  }
  out += fmt::format("#else\n  #declare {} = {};\n#end\n", var, num(t.values.back()));
  return out;
}

std::string pov_identifier(const std::string& name, size_t index) {
  const bool plain = std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
  return plain ? "ZS_P_" + name : "ZS_P" + std::to_string(index);
}

/// The coefficients of F as polynomials in the animated parameters' scaled values
/// u = (q − centre) / half ∈ [−1, 1]: c_ijk(u) = Σ_b fit(b, term) · u^basis[b].
struct CoefficientFit {
  std::vector<std::vector<int>> basis;           // exponents of u, one per basis monomial
  std::vector<std::tuple<int, int, int>> terms;  // (i, j, k) of x^i y^j z^k
  Eigen::MatrixXd fit;                           // basis × terms
  double scale = 0;                              // the largest coefficient seen
  int degree = 0;                                // in x, y, z
};

void monomials_up_to(int m, int d, std::vector<int>& e, size_t var,
                     std::vector<std::vector<int>>& out) {
  if (var == static_cast<size_t>(m)) {
    out.push_back(e);
    return;
  }
  for (int p = 0; p <= d; ++p) {
    e[var] = p;
    monomials_up_to(m, d - p, e, var + 1, out);
  }
  e[var] = 0;
}

double basis_value(const std::vector<double>& u, const std::vector<int>& exponents) {
  double v = 1;
  for (size_t k = 0; k < u.size(); ++k) v *= std::pow(u[k], exponents[k]);
  return v;
}

CoefficientFit fit_coefficients(Surface surface, const std::vector<const KeyTrack*>& animated,
                                const std::vector<double>& centre,
                                const std::vector<double>& half) {
  const int m = static_cast<int>(animated.size());
  // One fixed sequence of sample points; each degree tried uses its first points.
  std::mt19937_64 rng(20240607);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<std::vector<double>> points;
  std::vector<Polynomial> expansions;
  std::map<std::tuple<int, int, int>, int> column;
  CoefficientFit f;
  for (int d = 0; d <= kMaxParamDegree; ++d) {
    f.basis.clear();
    std::vector<int> e(static_cast<size_t>(m), 0);
    monomials_up_to(m, d, e, 0, f.basis);
    const size_t nb = f.basis.size(), ns = 2 * nb + 3, checks = 8;
    while (points.size() < ns + checks) {
      std::vector<double> u(static_cast<size_t>(m));
      for (double& x : u) x = uniform(rng);
      for (int k = 0; k < m; ++k)
        surface.field.set_parameter(animated[k]->name, centre[k] + half[k] * u[k]);
      expansions.push_back(detail::pov_polynomial(surface));
      for (const Monomial& t : expansions.back().terms())
        column.try_emplace({t.i, t.j, t.k}, static_cast<int>(column.size()));
      points.push_back(std::move(u));
    }
    Eigen::MatrixXd a(ns, nb), b = Eigen::MatrixXd::Zero(ns, column.size());
    for (size_t s = 0; s < ns; ++s) {
      for (size_t j = 0; j < nb; ++j) a(s, j) = basis_value(points[s], f.basis[j]);
      for (const Monomial& t : expansions[s].terms()) b(s, column.at({t.i, t.j, t.k})) = t.c;
    }
    f.fit = a.colPivHouseholderQr().solve(b);
    f.scale = b.cwiseAbs().maxCoeff();
    // Checked at further points the fit has not seen: an exact polynomial agrees to rounding,
    // an approximation (a root, a quotient of the parameters) does not.
    double residual = (a * f.fit - b).cwiseAbs().maxCoeff();
    for (size_t s = ns; s < points.size() && residual <= 1e-12 * f.scale; ++s) {
      Eigen::RowVectorXd row(nb), want = Eigen::RowVectorXd::Zero(b.cols());
      for (size_t j = 0; j < nb; ++j) row(j) = basis_value(points[s], f.basis[j]);
      for (const Monomial& t : expansions[s].terms()) want(column.at({t.i, t.j, t.k})) = t.c;
      residual = std::max(residual, (row * f.fit - want).cwiseAbs().maxCoeff());
    }
    if (residual <= 1e-12 * f.scale) {
      f.terms.assign(column.size(), {});
      for (const auto& [ijk, c] : column) f.terms[static_cast<size_t>(c)] = ijk;
      for (size_t s = 0; s < points.size(); ++s)
        f.degree = std::max(f.degree, expansions[s].degree());
      return f;
    }
  }
  std::string names;
  for (const KeyTrack* t : animated) names += (names.empty() ? "" : ", ") + t->name;
  throw BadInput(fmt::format(
      "POV-Ray animation: the coefficients of '{}' are not polynomials of degree ≤ {} in the "
      "animated parameters ({}), so POV-Ray cannot compute them from clock; export still "
      "scenes, one per frame, instead",
      surface.label(), kMaxParamDegree, names));
}

/// `#declare ZS_ortho = 0 | 1` at each keyframe that switches the projection, from its time on.
std::string projection_switches(const Keyframes& keys) {
  std::string out;
  for (size_t i = 1; i < keys.projections.size(); ++i)
    out += fmt::format("#if (clock >= {} - 1e-9)\n  #declare ZS_ortho = {};\n#end\n",
                       num(keys.projections[i].first),
                       keys.projections[i].second == Projection::orthographic ? 1 : 0);
  return out;
}

/// The camera of the frame at clock, as Camera::frame and View make it, then the lights.
std::string pov_camera_and_lights(const Surface& surface, const RenderOptions& options,
                                  const Keyframes& keys) {
  const Camera& base = detail::camera_of(surface, options);
  std::string out = "// The camera at clock (degrees and distances as zeroset's Camera).\n";
  const std::vector<std::pair<std::string, double>> fields = {
      {"azimuth_deg", base.azimuth_deg},
      {"elevation_deg", base.elevation_deg},
      {"distance", base.distance},
      {"roll_deg", base.roll_deg},
      {"fov_deg", base.fov_deg},
      {"ortho_height", base.view_height(surface.scene_radius())}};
  // The projection at clock: the surface's, or switched at keyframes (the last switch at or
  // before clock, the first one's before it; frame times are at least 1/65535 apart).
  const bool switches = !keys.projections.empty();
  const bool any_ortho =
      base.is_orthographic() ||
      std::any_of(keys.projections.begin(), keys.projections.end(),
                  [](const auto& p) { return p.second == Projection::orthographic; });
  for (const auto& field : fields) {
    if (field.first == "ortho_height" && !any_ortho) continue;
    const std::string& name = field.first;  // names of their own: the lambda captures `name`
    const double value = field.second;
    const auto t = std::find_if(keys.camera.begin(), keys.camera.end(),
                                [&](const KeyTrack& k) { return k.name == name; });
    out += t == keys.camera.end() ? fmt::format("#declare ZS_{} = {};\n", name, num(value))
                                  : pov_track(*t, "ZS_" + name);
  }
  const double aspect = static_cast<double>(options.width) / options.height;
  out += fmt::format(
      "#declare ZS_target = {};\n"
      "#declare ZS_az = radians(ZS_azimuth_deg);\n"
      "#declare ZS_el = radians(ZS_elevation_deg);\n"
      "#declare ZS_roll = radians(ZS_roll_deg);\n"
      "// Distance 0 fits the clip volume's ball into the vertical field of view.\n"
      "#declare ZS_dist = (ZS_distance > 0 ? ZS_distance : "
      "1.08 * {} / sin(radians(ZS_fov_deg) / 2));\n"
      "{}"
      "#declare ZS_eye = ZS_target + ZS_dist * <cos(ZS_el) * cos(ZS_az), "
      "cos(ZS_el) * sin(ZS_az), sin(ZS_el)>;\n"
      "#declare ZS_forward = vnormalize(ZS_target - ZS_eye);\n"
      "// z is up; looking straight up or down, the azimuth's direction is.\n"
      "#declare ZS_right0 = vcross(ZS_forward, z);\n"
      "#if (vlength(ZS_right0) < 1e-9)\n"
      "  #declare ZS_right0 = vcross(ZS_forward, <-cos(ZS_az), -sin(ZS_az), 0>);\n"
      "#end\n"
      "#declare ZS_right0 = vnormalize(ZS_right0);\n"
      "#declare ZS_up0 = vnormalize(vcross(ZS_right0, ZS_forward));\n"
      "#declare ZS_right = cos(ZS_roll) * ZS_right0 + sin(ZS_roll) * ZS_up0;\n"
      "#declare ZS_up = -sin(ZS_roll) * ZS_right0 + cos(ZS_roll) * ZS_up0;\n"
      "// POV-Ray's camera is left-handed: a negative `right` makes it right-handed, as ours;\n"
      "// `angle` is the horizontal field of view.\n",
      pov_vec(base.target), num(surface.scene_radius()),
      !any_ortho ? std::string()
      : switches ? fmt::format("#declare ZS_ortho = {};\n{}"
                               "// Orthographic: the rays start outside the clip volume.\n"
                               "#if (ZS_ortho)\n  #declare ZS_dist = max(ZS_dist, {});\n#end\n",
                               keys.projections.front().second == Projection::orthographic ? 1 : 0,
                               projection_switches(keys), num(2.5 * surface.scene_radius()))
                 : fmt::format("// Orthographic: the rays start outside the clip volume.\n"
                               "#declare ZS_dist = max(ZS_dist, {});\n",
                               num(2.5 * surface.scene_radius())));
  const std::string orthographic = fmt::format(
      "camera {{\n  orthographic\n  location ZS_eye\n  sky ZS_up\n"
      "  up <0, ZS_ortho_height, 0>\n  right <{} * ZS_ortho_height, 0, 0>\n"
      "  look_at ZS_target\n}}\n",
      num(-aspect));
  const std::string perspective = fmt::format(
      "camera {{\n  perspective\n  location ZS_eye\n  sky ZS_up\n"
      "  up <0, 1, 0>\n  right <{}, 0, 0>\n"
      "  angle 2 * degrees(atan(tan(radians(ZS_fov_deg) / 2) * {}))\n"
      "  look_at ZS_target\n}}\n",
      num(-aspect), num(aspect));
  if (switches)
    out += "#if (ZS_ortho)\n" + orthographic + "#else\n" + perspective + "#end\n\n";
  else
    out += (base.is_orthographic() ? orthographic : perspective) + "\n";
  // Lights as world_lights places them: those that follow the camera turn with it.
  const double far = 1000.0 * surface.scene_radius();
  for (const Light& l : options.lights.empty() ? default_lights() : options.lights) {
    if (!(l.direction.norm() > 0 && l.direction.allFinite())) continue;
    const std::string dir =
        l.follows_camera
            ? fmt::format("vnormalize({} * ZS_right + {} * ZS_up - {} * ZS_forward)",
                          num(l.direction.x()), num(l.direction.y()), num(l.direction.z()))
            : "vnormalize(" + pov_vec(l.direction) + ")";
    out += fmt::format(
        "light_source {{ ZS_target + {} * {} color rgb {} parallel point_at ZS_target "
        "shadowless }}\n",
        num(far), dir, pov_vec(l.color));
  }
  return out;
}

}  // namespace

std::string pov_animation_scene(const Surface& surface, const RenderOptions& options,
                                const Keyframes& keys) {
  detail::validate(options);
  const Surface start = keys.at(surface, 0.0);
  const Polynomial first = detail::pov_polynomial(start);
  // The parameters that move, and the box their values stay in (eased values stay between
  // the keyframes').
  std::vector<const KeyTrack*> animated;
  std::vector<double> centre, half;
  for (const KeyTrack& t : keys.params) {
    const auto [lo, hi] = std::minmax_element(t.values.begin(), t.values.end());
    if (*lo == *hi) continue;
    animated.push_back(&t);
    centre.push_back(0.5 * (*lo + *hi));
    half.push_back(0.5 * (*hi - *lo));
  }
  // The scene's clip is written once, from the surface's values: one sized by a moving
  // parameter would be wrong in every other frame.
  for (const ClipFormula& f : surface.clip.formulas)
    for (const Field& number : f.numbers)
      for (const KeyTrack* t : animated)
        if (number.parameter_index(t->name) >= 0)
          throw BadInput(fmt::format(
              "POV-Ray animation: the clip '{}' changes with the animated parameter '{}', and "
              "the scene's clip is fixed; export still scenes, one per frame, instead",
              f.spec, t->name));
  std::string out;
  out += fmt::format("// {} — a keyframed animation exported by zeroset\n", surface.label());
  out += fmt::format("// F at the first frame = {}\n", first.to_string());
  out += "// Render the frames with the .ini file written beside this one: povray NAME.ini\n";
  out += "// clock runs from 0 at the first frame to 1 at the last.\n";
  out += detail::pov_preamble(options);
  for (size_t i = 0; i < keys.params.size(); ++i)
    out += pov_track(keys.params[i], pov_identifier(keys.params[i].name, i));
  out += pov_camera_and_lights(surface, options, keys);

  std::vector<detail::PovTerm> terms;
  int degree = first.degree();
  if (animated.empty()) {
    for (const Monomial& m : first.terms()) terms.push_back({m.i, m.j, m.k, num(m.c)});
  } else {
    const CoefficientFit f = fit_coefficients(surface, animated, centre, half);
    degree = f.degree;
    out += "\n// The animated parameters scaled to [-1, 1].\n";
    std::vector<std::string> u;
    for (size_t k = 0; k < animated.size(); ++k) {
      u.push_back("ZS_u" + std::to_string(k));
      const size_t index = static_cast<size_t>(animated[k] - keys.params.data());
      out += fmt::format("#declare {} = ({} - {}) / {};\n", u.back(),
                         pov_identifier(animated[k]->name, index), num(centre[k]), num(half[k]));
    }
    for (size_t t = 0; t < f.terms.size(); ++t) {
      std::string c;
      for (size_t b = 0; b < f.basis.size(); ++b) {
        const double a = f.fit(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(t));
        if (std::abs(a) <= 1e-14 * f.scale) continue;  // rounding of the fit
        std::string term = num(a);
        for (size_t k = 0; k < u.size(); ++k) {
          const int p = f.basis[b][k];
          if (p == 1) term += " * " + u[k];
          if (p > 1) term += fmt::format(" * pow({}, {})", u[k], p);
        }
        c += (c.empty() ? "" : " + ") + term;
      }
      if (c.empty()) continue;
      const auto [i, j, k] = f.terms[t];
      terms.push_back({i, j, k, "(" + c + ")"});
    }
  }
  out += detail::pov_polynomial_object(degree, terms, surface, options);
  return out;
}

std::string pov_animation_ini(const std::string& pov_file, const std::string& output_prefix,
                              const RenderOptions& options, const PovFrames& frames) {
  if (frames.frames < 1 || frames.first < 0 || frames.first > frames.last ||
      frames.last >= frames.frames)
    throw InvalidArgument("frames",
                          fmt::format("{}-{} of {}", frames.first, frames.last, frames.frames),
                          "expected 0 ≤ first ≤ last < frames");
  std::string out = "; Renders the animation's frames: povray THIS_FILE.ini (written by zeroset)\n";
  out += fmt::format("Input_File_Name={}\nOutput_File_Name={}\nOutput_File_Type=N\n", pov_file,
                     output_prefix);
  out += fmt::format("Width={}\nHeight={}\nAntialias=On\nAntialias_Threshold=0.1\n", options.width,
                     options.height);
  // Frame f at clock f / (frames − 1), numbered from 0 as zeroset animate's frames.
  out += fmt::format("Initial_Frame=0\nFinal_Frame={}\nInitial_Clock=0\nFinal_Clock=1\n",
                     frames.frames - 1);
  out += "Cyclic_Animation=Off\n";
  if (frames.first != 0 || frames.last != frames.frames - 1)
    out += fmt::format("Subset_Start_Frame={}\nSubset_End_Frame={}\n", frames.first, frames.last);
  return out;
}

void write_pov_animation(const Surface& surface, const RenderOptions& options,
                         const Keyframes& keys, const PovFrames& frames,
                         const std::string& pov_path) {
  const std::filesystem::path pov(pov_path);
  std::filesystem::path ini = pov;
  ini.replace_extension(".ini");
  // Both texts before either file: an error leaves no file behind.
  const std::string scene = pov_animation_scene(surface, options, keys);
  const std::string settings =
      pov_animation_ini(pov.filename().string(), pov.stem().string() + "_", options, frames);
  write_file_atomically(pov_path, [&](std::ostream& o) { o << scene; });
  write_file_atomically(ini.string(), [&](std::ostream& o) { o << settings; });
}

}  // namespace zeroset

// zeroset list | info | eval: what the catalog holds, what a surface is, and F at a point.
#include <fmt/core.h>

#include <cmath>

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::cli {
namespace {

Vec3 parse_point(const std::string& text) {
  std::vector<double> v;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = text.substr(pos, comma - pos);
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(d))
      throw InvalidArgument("--at", text, fmt::format("'{}' is not a finite number", item));
    v.push_back(d);
    pos = comma + 1;
  }
  if (v.size() != 3) throw InvalidArgument("--at", text, "expected three numbers x,y,z");
  return {v[0], v[1], v[2]};
}

std::string fmt_vec(const Vec3& v) {
  return fmt::format("({:.10g}, {:.10g}, {:.10g})", v.x(), v.y(), v.z());
}

void run_list() {
  for (const auto& e : catalog()) {
    std::string params;
    for (const auto& p : e.params) params += fmt::format(" {}={:g}", p.name, p.value);
    fmt::print("{:<9} {}{}\n", e.name, e.title, params.empty() ? "" : " —" + params);
  }
}

// The singular set found numerically: one line per curve and per special point.
void print_singular_set(const Surface& s) {
  if (!s.clip.is_bounded()) {
    fmt::print("singular set: not searched (no bounded clip; give --clip sphere:R)\n");
    return;
  }
  const SingularSet set = find_singular_set(s);
  // Coordinates within rounding of zero print as 0.
  const double tiny = 1e-14 * s.scene_radius();
  auto show = [&](Vec3 p) {
    for (int a = 0; a < 3; ++a)
      if (std::abs(p[a]) < tiny) p[a] = 0;
    return fmt_vec(p);
  };
  fmt::print("singular set (found): {}\n", singular_set_summary(set));
  if (set.has_singular_sheet) {
    fmt::print("  for example at {}: sampling and meshing see no sign change there\n",
               fmt_vec(set.singular_sheet_example));
    return;
  }
  for (const SingularCurve& c : set.curves)
    fmt::print("  {:<10} curve  length {:.6g}{}  {} .. {}\n", to_string(c.kind), c.length(),
               c.closed ? " (closed)" : "", show(c.points.front()), show(c.points.back()));
  for (const SingularPoint& p : set.points)
    fmt::print("  {:<10} point  {}\n", to_string(p.kind), show(p.position));
}

void run_info(const SurfaceArgs& args, bool as_json) {
  const Scene scene = args.resolve();
  const Surface& s = scene.surface;
  Evaluator ev(s.field);
  const auto sing = s.singular_points();
  if (as_json) {
    nlohmann::json j = scene_to_json(scene);
    j["degree"] = s.field.degree();
    j["is_polynomial"] = s.field.is_polynomial();
    nlohmann::json pts = nlohmann::json::array();
    for (const Vec3& p : sing) {
      Vec3 g;
      const double f = ev.value_gradient(p, g);
      pts.push_back({{"point", json_read::from_vec3(p)}, {"F", f}, {"grad_norm", g.norm()}});
    }
    j["singular_points"] = pts;
    if (s.clip.is_bounded()) j["singular_set"] = singular_set_json(find_singular_set(s));
    fmt::print("{}\n", j.dump(2));
    return;
  }
  if (!s.title.empty()) fmt::print("{} ({})\n", s.title, s.name);
  fmt::print("equation:   {}\n", s.field.expression_string());
  if (s.field.is_expandable())
    fmt::print("degree:     {} (polynomial, {} terms expanded)\n", s.field.degree(),
               s.field.polynomial().terms().size());
  else if (s.field.is_polynomial())
    fmt::print(
        "degree:     {} (polynomial, not expanded above degree {}: ray tracing uses "
        "interval arithmetic, no POV-Ray export)\n",
        s.field.degree(), Field::kMaxExpansionDegree);
  else
    fmt::print("degree:     not a polynomial (ray tracing uses interval arithmetic)\n");
  if (s.ranges.empty()) fmt::print("parameters: none\n");
  for (const auto& r : s.ranges)
    fmt::print("parameter:  {} = {:g}   (range {:g} .. {:g})\n", r.name,
               s.field.parameter_values()[s.field.parameter_index(r.name)], r.min, r.max);
  if (s.clip.is_empty_spec())
    fmt::print(
        "clip:       none (unbounded: give --clip sphere:R for sampling, meshing, "
        "rendering)\n");
  for (const auto& c : s.clip.to_specs()) fmt::print("clip:       {}\n", c);
  if (s.clip.is_parametric())  // sized by the parameters: what that gives now
    for (const auto& c : s.clip.to_specs(true)) fmt::print("clip now:   {}\n", c);
  if (!s.singular_points_fn) {
    fmt::print("singular points: none known\n");
  } else {
    fmt::print("singular points: {} known inside the clip\n", sing.size());
    for (const Vec3& p : sing) {
      Vec3 g;
      const double f = ev.value_gradient(p, g);
      fmt::print("  {}   F = {:.1e}  |grad F| = {:.1e}\n", fmt_vec(p), f, g.norm());
    }
  }
  print_singular_set(s);
}

void run_eval(const SurfaceArgs& args, const std::vector<std::string>& at, bool as_json) {
  const Scene scene = args.resolve();
  const Surface& s = scene.surface;
  Evaluator ev(s.field);
  nlohmann::json out = nlohmann::json::array();
  for (const auto& text : at) {
    const Vec3 p = parse_point(text);
    const FieldSample r = ev.sample(p, Derivatives::kAll);
    if (as_json) {
      nlohmann::json j;
      j["point"] = json_read::from_vec3(p);
      j["value"] = r.value;
      j["gradient"] = {r.gradient.x(), r.gradient.y(), r.gradient.z()};
      j["hessian"] = nlohmann::json::array();
      for (int i = 0; i < 3; ++i)
        j["hessian"].push_back({r.hessian(i, 0), r.hessian(i, 1), r.hessian(i, 2)});
      for (size_t k = 0; k < r.dq.size(); ++k) j["dF_d" + s.field.parameter_names()[k]] = r.dq[k];
      out.push_back(j);
      continue;
    }
    fmt::print("at        {}\n", fmt_vec(p));
    fmt::print("F         {:.12g}\n", r.value);
    fmt::print("grad F    {}   |grad F| = {:.6g}\n", fmt_vec(r.gradient), r.gradient.norm());
    for (int i = 0; i < 3; ++i)
      fmt::print("{}  [{:16.10g} {:16.10g} {:16.10g}]\n", i == 0 ? "Hessian " : "        ",
                 r.hessian(i, 0), r.hessian(i, 1), r.hessian(i, 2));
    for (size_t k = 0; k < r.dq.size(); ++k)
      fmt::print("dF/d{:<5} {:.12g}\n", s.field.parameter_names()[k], r.dq[k]);
    if (std::abs(r.gradient.norm()) > 0)
      fmt::print("distance  ~{:.3g}  (|F|/|grad F|, first order)\n",
                 std::abs(r.value) / r.gradient.norm());
  }
  if (as_json) fmt::print("{}\n", out.size() == 1 ? out[0].dump(2) : out.dump(2));
}

}  // namespace

void register_catalog_commands(CLI::App& app) {
  auto* list = app.add_subcommand("list", "List the catalog of named surfaces, one per line");
  list->callback([] { run_list(); });

  auto* info = app.add_subcommand(
      "info",
      "Show a surface: equation, degree, parameters, clip and known singular points\n"
      "  e.g. zeroset info kummer --param mu=2\n"
      "       zeroset info \"x^2 + y^2 = z^2\" --clip sphere:1");
  auto info_args = std::make_shared<SurfaceArgs>();
  auto info_json = std::make_shared<bool>(false);
  info_args->add_to(info);
  info->add_flag("--json", *info_json, "Print machine-readable JSON");
  info->callback([info_args, info_json] { run_info(*info_args, *info_json); });

  auto* eval = app.add_subcommand(
      "eval",
      "Evaluate F, its gradient, Hessian and parameter derivatives at points\n"
      "  e.g. zeroset eval kummer --param mu=1.5 --at 1.0606601718,-0.3535533906,-0.5");
  auto eval_args = std::make_shared<SurfaceArgs>();
  auto at = std::make_shared<std::vector<std::string>>();
  auto eval_json = std::make_shared<bool>(false);
  eval_args->add_to(eval);
  eval->add_option("--at", *at, "Point x,y,z (repeatable)")->required()->type_name("X,Y,Z");
  eval->add_flag("--json", *eval_json, "Print machine-readable JSON");
  eval->callback([eval_args, at, eval_json] { run_eval(*eval_args, *at, *eval_json); });
}

}  // namespace zeroset::cli

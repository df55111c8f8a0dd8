#include "common.h"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/settings.h"

namespace zeroset::cli {

GlobalFlags& global_flags() {
  static GlobalFlags flags;
  return flags;
}

void say(const std::string& line) {
  if (!global_flags().quiet) fmt::print("{}\n", line);
}

void warn(const std::string& line) {
  if (!global_flags().quiet) fmt::print(stderr, "zeroset: warning: {}\n", line);
}

void add_show_singular_flag(CLI::App* cmd, bool& flag, const std::string& pictures) {
  cmd->add_flag("--show-singular", flag,
                "Draw the singular set (where F = 0 and ∇F = 0, as `zeroset info` lists it) "
                "over " +
                    pictures +
                    ": curves as thin tubes, green where two sheets cross, "
                    "magenta where the curve is isolated (no sheet through it, e.g. Whitney's "
                    "handle; the surface alone would not show it), cyan where degenerate (e.g. a "
                    "cuspidal edge); special points as small spheres, black: node, red: pinch "
                    "point, yellow: triple point, grey: a curve leaves the clip, cyan: degenerate "
                    "point. Whatever is in front hides them");
}

void warn_if_singular_sheet(const Surface& surface, const std::optional<SingularSet>& known) {
  if (auto line = singular_sheet_warning(surface, known ? &*known : nullptr)) warn(*line);
}

FieldSurvey survey_and_warn(const Surface& surface) {
  const FieldSurvey survey = survey_field(surface);
  if (const auto line = survey_warning(surface, survey)) warn(*line);
  return survey;
}

nlohmann::json singular_stats(const std::optional<SingularSet>& set) {
  return set ? singular_set_json(*set, false) : nlohmann::json();
}

void SurfaceArgs::add_to(CLI::App* cmd, bool optional) {
  auto* opt = cmd->add_option("SURFACE", spec,
                              "Catalog name (zeroset list), equation in quotes, scene file "
                              "(.json) or SURFER file (.jsurf)");
  if (!optional) opt->required();
  cmd->add_option("-p,--param", params,
                  "Parameter value name=value (repeatable), e.g. --param mu=1.5")
      ->type_name("NAME=VALUE");
  cmd->add_option("--clip", clips,
                  "Clip volume, replaces the default (repeatable, intersected): sphere:R, "
                  "sphere:R@x,y,z, box:H, box:x0,y0,z0,x1,y1,z1, plane:nx,ny,nz,d (keeps "
                  "n.x <= d)")
      ->type_name("SPEC");
}

SurfaceOverrides SurfaceArgs::overrides() const {
  SurfaceOverrides o;
  for (const auto& p : params) {
    auto [name, value] = parse_assignment(p, "--param");
    add_parameter_override(o, name, value, "--param", p);
  }
  o.clip_specs = clips;
  return o;
}

Scene SurfaceArgs::resolve() const { return resolve_scene(spec, overrides()); }

namespace {
double parse_finite(const std::string& text, const std::string& flag, const std::string& whole) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size())
    throw InvalidArgument(flag, whole, fmt::format("'{}' is not a number", text));
  if (!std::isfinite(v)) throw InvalidArgument(flag, whole, "the value must be finite");
  return v;
}
}  // namespace

std::pair<std::string, double> parse_assignment(const std::string& text, const std::string& flag) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InvalidArgument(flag, text, "expected name=value, e.g. mu=1.5");
  return {text.substr(0, eq), parse_finite(text.substr(eq + 1), flag, text)};
}

void add_parameter_override(SurfaceOverrides& o, const std::string& name, double value,
                            const std::string& flag, const std::string& text) {
  // Keeping the last of two values would hide a mistake in a long command line.
  if (!o.params.emplace(name, value).second)
    throw InvalidArgument(flag, text, fmt::format("parameter '{}' is given more than once", name));
}

ParamRange parse_range(const std::string& text, const std::string& flag) {
  const size_t eq = text.find('=');
  const size_t colon = text.find(':', eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos)
    throw InvalidArgument(flag, text, "expected name=from:to, e.g. mu=1.02:2.44");
  ParamRange r;
  r.name = text.substr(0, eq);
  r.from = parse_finite(text.substr(eq + 1, colon - eq - 1), flag, text);
  r.to = parse_finite(text.substr(colon + 1), flag, text);
  // A parameter's range ends obey the parameter values' limit (zeroset/expr/field.h).
  for (double end : {r.from, r.to}) {
    try {
      check_parameter_value(r.name, end);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(flag, text, e.what());
    }
  }
  return r;
}

FrameRange parse_frame_range(const std::string& text, int frames, const std::string& flag) {
  check_flag_range("--frames", frames, 1, kMaxFrames);
  if (text.empty()) return {0, frames - 1};
  // Digits only: a sign, a decimal point or an exponent is refused, not rounded.
  const auto frame_number = [&](const std::string& part) {
    if (part.empty() || part.size() > 9 ||
        part.find_first_not_of("0123456789") != std::string::npos)
      throw InvalidArgument(flag, text,
                            fmt::format("expected FIRST-LAST, whole frame numbers from 0 to {} "
                                        "(frames count from 0), e.g. 0-{}",
                                        frames - 1, std::min(9, frames - 1)));
    return std::stoi(part);
  };
  const size_t dash = text.find('-');
  FrameRange r;
  r.first = frame_number(text.substr(0, dash));
  r.last = dash == std::string::npos ? r.first : frame_number(text.substr(dash + 1));
  if (r.first > r.last) throw InvalidArgument(flag, text, "the first frame comes after the last");
  if (r.last >= frames)
    throw InvalidArgument(
        flag, text,
        fmt::format("the animation has {} frames, numbered 0 to {}", frames, frames - 1));
  return r;
}

void check_flag_range(const std::string& flag, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi))
    throw InvalidArgument(flag, fmt::format("{}", value),
                          fmt::format("must lie in [{:g}, {:g}]", lo, hi));
}

std::pair<int, int> parse_size(const std::string& text, const std::string& flag) {
  const size_t x = text.find('x');
  if (x == std::string::npos)
    throw InvalidArgument(flag, text, "expected WIDTHxHEIGHT, e.g. 800x600");
  const double w = parse_finite(text.substr(0, x), flag, text);
  const double h = parse_finite(text.substr(x + 1), flag, text);
  if (w != std::floor(w) || h != std::floor(h))
    throw InvalidArgument(flag, text, "width and height must be whole numbers");
  try {
    validate_image_size(static_cast<long long>(std::clamp(w, -1e15, 1e15)),
                        static_cast<long long>(std::clamp(h, -1e15, 1e15)));
  } catch (const SettingError& e) {
    throw InvalidArgument(flag, text, e.why());
  }
  return {static_cast<int>(w), static_cast<int>(h)};
}

void validate_flags(const std::function<void()>& validate, FlagNames flags) {
  try {
    validate();
  } catch (const SettingError& e) {
    throw InvalidArgument(flag_name(flags, e.key()), e.value(), e.why());
  }
}

std::string flag_name(FlagNames flags, std::string_view key) {
  for (const auto& [k, name] : flags)
    if (k == key) return std::string(name);
  return std::string(key);
}

std::vector<double> parse_numbers(const std::string& text, const std::string& flag) {
  std::vector<double> v;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t comma = text.find(',', pos);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = text.substr(pos, comma - pos);
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(d))
      throw InvalidArgument(flag, text, fmt::format("'{}' is not a finite number", item));
    v.push_back(d);
    pos = comma + 1;
  }
  return v;
}

Camera with_camera_flag(Camera camera, const std::string& spec) {
  if (spec.empty()) return camera;
  const std::vector<double> v = parse_numbers(spec, "--camera");
  if (v.size() < 2 || v.size() > 4)
    throw InvalidArgument("--camera", spec, "expected AZIMUTH,ELEVATION[,DISTANCE[,ROLL]]");
  camera.azimuth_deg = v[0];
  camera.elevation_deg = v[1];
  if (v.size() >= 3) camera.distance = v[2];
  // The flag gives the whole orientation: a scene file's roll does not stay behind.
  camera.roll_deg = v.size() == 4 ? v[3] : 0.0;
  validate_flags([&] { validate_camera(camera); }, {{"azimuth_deg", "--camera azimuth"},
                                                    {"elevation_deg", "--camera elevation"},
                                                    {"distance", "--camera distance"},
                                                    {"roll_deg", "--camera roll"}});
  return camera;
}

Camera with_projection_flag(Camera camera, const std::string& spec) {
  return spec.empty() ? camera : with_projection(camera, spec, "--projection");
}

Progress::Progress(std::string label, bool quiet)
    : label_(std::move(label)), enabled_(!quiet && ::isatty(STDERR_FILENO)) {}

Progress::~Progress() { finish(); }

void Progress::update(double fraction) {
  if (!enabled_) return;
  const int permille = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 1000);
  if (permille == last_permille_) return;
  last_permille_ = permille;
  const int width = 30, filled = permille * width / 1000;
  fmt::print(stderr, "\r{} [{}{}] {:5.1f}%", label_, std::string(filled, '#'),
             std::string(width - filled, ' '), permille / 10.0);
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || last_permille_ < 0) return;
  fmt::print(stderr, "\r{}\r", std::string(label_.size() + 45, ' '));
  std::fflush(stderr);
  last_permille_ = -1;
}

void write_json(const nlohmann::json& j, const std::string& path) {
  const std::string text = j.dump(2) + "\n";
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace zeroset::cli

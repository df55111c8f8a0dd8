#include "commands.h"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "zeroset/error.h"

namespace zeroset::viewer {

const std::vector<CommandInfo>& command_table() {
  static const std::vector<CommandInfo> table = {
      // surface
      {"equation", 1, -1, "equation TEXT", "type an equation (the rest of the line)"},
      {"catalog", 1, 1, "catalog NAME", "open a catalog surface with its defaults"},
      {"load", 1, 1, "load FILE.json", "open a scene file"},
      {"param", 2, 2, "param NAME VALUE", "set a parameter"},
      {"range", 3, 3, "range NAME MIN MAX", "set a parameter's slider range"},
      {"clip", 1, -1, "clip SPEC...", "replace the clip: sphere:R, box:H, plane:nx,ny,nz,d, ..."},
      // modes and animation
      {"mode", 1, 1, "mode floaters|mesh|raytrace", "switch what the view shows"},
      {"play", 0, 1, "play [NAME]", "animate a parameter through its range"},
      {"pause", 0, 0, "pause", "stop the animation"},
      {"loop", 1, 1, "loop on|off", "animate back and forth, or stop at the end"},
      {"speed", 1, 1, "speed RANGES_PER_SECOND", "animation speed (0.1: one sweep in 10 s)"},
      {"floaters", 1, -1, "floaters KEY=VALUE... | floaters reset",
       "max_count, radius (σ̂, 0 auto), cos_weight, radius_adapt (wh|curvature|singular|mixed), "
       "clip_projection, snap_to_nodes, seed"},
      {"mesh", 1, -1, "mesh KEY=VALUE...", "cells, improve (on|off), max_steps"},
      {"draw", 1, 1, "draw disks|points", "how floaters are drawn"},
      {"disk-scale", 1, 1, "disk-scale S", "disk radius as a multiple of the floater radius"},
      {"point-size", 1, 1, "point-size PIXELS", "size of floaters drawn as points"},
      {"wireframe", 1, 1, "wireframe on|off", "overlay the mesh edges"},
      {"lights", 1, 1, "lights follow|fixed", "lights follow the camera, or stay in the world"},
      {"color", 4, 4, "color front|back|background R G B", "a colour (components in [0, 1])"},
      // camera
      {"camera", 2, 3, "camera AZIMUTH ELEVATION [DISTANCE]", "set the orbit camera (degrees)"},
      {"orbit", 2, 2, "orbit D_AZIMUTH D_ELEVATION", "turn the camera (degrees)"},
      {"zoom", 1, 1, "zoom FACTOR", "come closer by FACTOR (< 1 moves away)"},
      {"pan", 2, 2, "pan DX DY", "move the picture by pixels"},
      {"reset-view", 0, 0, "reset-view", "back to the surface's camera"},
      // files
      {"save-scene", 1, 1, "save-scene FILE.json", "surface, camera and settings"},
      {"save-mesh", 1, 1, "save-mesh FILE.ply|obj|stl", "the current mesh (mesh mode)"},
      {"save-floaters", 1, 1, "save-floaters FILE.ply", "the current floaters (floaters mode)"},
      {"save-pov", 1, 1, "save-pov FILE.pov", "the view as a POV-Ray scene"},
      // frame loop
      {"frames", 1, 1, "frames N", "run N frames", true},
      {"wait", 0, 1, "wait [SECONDS]",
       "run frames until the mode's work is done (default: at most 60 s)", true},
      {"steps", 1, 2, "steps N [SECONDS]", "run frames until the floaters took N more steps",
       true},
      {"sleep", 1, 1, "sleep SECONDS", "run frames for this long", true},
      {"screenshot", 1, 1, "screenshot FILE.png", "save the next frame", true},
      {"ui", 1, 1, "ui on|off", "show or hide the panel", true},
      {"stats", 0, 0, "stats", "print the live statistics as one JSON line", true},
      {"expect-error", 0, -1, "expect-error [TEXT]",
       "the previous command must have failed (with TEXT in its message)", true},
      {"quit", 0, 0, "quit", "close the viewer", true},
  };
  return table;
}

const CommandInfo* find_command(std::string_view name) {
  for (const auto& c : command_table())
    if (c.name == name) return &c;
  return nullptr;
}

CommandLine split_command(std::string_view line) {
  CommandLine out;
  auto is_blank = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  size_t i = 0;
  while (i < line.size() && is_blank(line[i])) ++i;
  if (i == line.size() || line[i] == '#') return out;
  const size_t name_end = std::find_if(line.begin() + i, line.end(), is_blank) - line.begin();
  out.name = std::string(line.substr(i, name_end - i));
  std::string_view rest = line.substr(name_end);
  while (!rest.empty() && is_blank(rest.front())) rest.remove_prefix(1);
  while (!rest.empty() && is_blank(rest.back())) rest.remove_suffix(1);
  out.rest = std::string(rest);
  size_t j = 0;
  while (j < rest.size()) {
    while (j < rest.size() && is_blank(rest[j])) ++j;
    const size_t k = std::find_if(rest.begin() + j, rest.end(), is_blank) - rest.begin();
    if (k > j) out.args.emplace_back(rest.substr(j, k - j));
    j = k;
  }
  return out;
}

const CommandInfo& check_command(const CommandLine& command) {
  const CommandInfo* info = find_command(command.name);
  if (!info) {
    std::string names;
    for (const auto& c : command_table()) names += (names.empty() ? "" : ", ") + std::string(c.name);
    throw InvalidArgument(fmt::format("unknown command '{}' (commands: {})", command.name, names));
  }
  const int n = static_cast<int>(command.args.size());
  if (n < info->min_args || (info->max_args >= 0 && n > info->max_args))
    throw InvalidArgument(fmt::format("'{}' takes {}: usage: {}", command.name,
                                      info->min_args == info->max_args
                                          ? fmt::format("{} argument(s)", info->min_args)
                                      : info->max_args < 0
                                          ? fmt::format("at least {} argument(s)", info->min_args)
                                          : fmt::format("{} to {} arguments", info->min_args,
                                                        info->max_args),
                                      info->usage));
  return *info;
}

bool parse_on_off(std::string_view text, std::string_view what) {
  if (text == "on" || text == "true" || text == "yes" || text == "1") return true;
  if (text == "off" || text == "false" || text == "no" || text == "0") return false;
  throw InvalidArgument(std::string(what), std::string(text), "expected on or off");
}

double parse_number(std::string_view text, std::string_view what) {
  double v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw InvalidArgument(std::string(what), std::string(text), "not a number");
  if (!std::isfinite(v)) throw InvalidArgument(std::string(what), std::string(text), "must be finite");
  return v;
}

long long parse_integer(std::string_view text, std::string_view what, long long lo, long long hi) {
  long long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw InvalidArgument(std::string(what), std::string(text), "not a whole number");
  if (v < lo || v > hi)
    throw InvalidArgument(std::string(what), std::string(text),
                          fmt::format("must lie in [{}, {}]", lo, hi));
  return v;
}

}  // namespace zeroset::viewer

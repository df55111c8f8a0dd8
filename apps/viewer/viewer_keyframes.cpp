// The viewer's keyframes: kept as the scene file's entries (so a loaded scene is saved back as
// it came), recorded from the current parameters and camera, and played through the tracks
// `zeroset animate` reads from them (read_keyframes), so both show the same animation.
#include <fmt/core.h>

#include <algorithm>
#include <climits>

#include "viewer_state.h"
#include "viewer_state_detail.h"
#include "zeroset/error.h"

namespace zeroset::viewer {
namespace {

using json = nlohmann::json;

// `zeroset animate`'s default frame count, which places keyframes given by frame.
constexpr int kDefaultFrames = 60;

json settings_with(const json& keys) { return json{{"animation", {{"keyframes", keys}}}}; }

double entry_time(const json& entry, int frames) {
  if (entry.contains("time")) return entry["time"].get<double>();
  return frame_time(entry["frame"].get<int>(), frames);
}

void check_time(double time) {
  if (!(time >= 0 && time <= 1))
    throw InvalidArgument("keyframe time", fmt::format("{}", time),
                          "must lie in [0, 1] (0: the first frame, 1: the last)");
}

}  // namespace

namespace detail {

json scene_keyframes(const json& settings) {
  if (!settings.is_object() || !settings.contains("animation")) return json::array();
  const json& a = settings["animation"];
  if (!a.is_object() || !a.contains("keyframes")) return json::array();
  return a["keyframes"];
}

int keyframe_frames(const json& keys) {
  double last = 0;  // read_keyframes checks each frame is whole; here only the largest counts
  if (keys.is_array())
    for (const json& k : keys)
      if (k.is_object() && k.contains("frame") && k["frame"].is_number())
        last = std::max(last, k["frame"].get<double>());
  return static_cast<int>(std::clamp<double>(last + 1, kDefaultFrames, INT_MAX));
}

}  // namespace detail

int ViewerState::keyframe_frames() const { return detail::keyframe_frames(keyframes_); }

double ViewerState::keyframe_time(std::size_t index, std::optional<int> frames) const {
  return entry_time(keyframes_.at(index), frames ? *frames : keyframe_frames());
}

Ease ViewerState::keyframe_ease(std::size_t index) const {
  const json& k = keyframes_.at(index);
  return k.contains("ease") ? find_ease(k["ease"].get<std::string>()).value_or(Ease::kInOut)
                            : Ease::kInOut;
}

Keyframes ViewerState::keyframe_tracks() const {
  if (keyframes_.empty()) return {};
  return read_keyframes(settings_with(keyframes_), surface_, keyframe_frames(), "keyframes");
}

void ViewerState::replace_keyframes(json keys) {
  // The same reader as scene files and `zeroset animate`: what it refuses is never kept.
  if (!keys.empty())
    (void)read_keyframes(settings_with(keys), surface_, detail::keyframe_frames(keys), "keyframes");
  keyframes_ = std::move(keys);
}

namespace {

// The keyframe index of a command or the panel, with the valid range in the message.
void check_index(std::size_t index, std::size_t count) {
  if (count == 0) throw InvalidArgument("there are no keyframes (keyframe add TIME records one)");
  if (index >= count)
    throw InvalidArgument("keyframe index", std::to_string(index),
                          fmt::format("expected 0 to {}", count - 1));
}

// A keyframe entry (without its time) from `s`: every parameter's value and the camera fields a
// keyframe may set.
json entry_of(const Surface& s, Ease ease) {
  json params = json::object();
  for (const ParamSpec& r : s.ranges)
    params[r.name] = s.field.parameter_values()[s.field.parameter_index(r.name)];
  const Camera& c = s.camera;
  return {{"params", params},
          {"camera",
           {{"azimuth_deg", c.azimuth_deg},
            {"elevation_deg", c.elevation_deg},
            {"distance", c.distance},
            {"roll_deg", c.roll_deg},
            {"fov_deg", c.fov_deg}}},
          {"ease", ease_name(ease)}};
}

}  // namespace

bool ViewerState::add_keyframe(double time, std::optional<Ease> ease) {
  return guard("keyframe add", [&] {
    check_time(time);
    const int frames = keyframe_frames();
    std::size_t at = 0;
    for (; at < keyframes_.size(); ++at) {
      const double t = entry_time(keyframes_[at], frames);
      if (t == time)
        throw InvalidArgument(
            fmt::format("keyframe {} is at time {} already (keyframe update {} "
                        "records the current state into it)",
                        at, time, at));
      if (t > time) break;
    }
    json keys = keyframes_;
    keys.insert(keys.begin() + static_cast<std::ptrdiff_t>(at),
                entry_of(surface_, ease.value_or(Ease::kInOut)));
    keys[at]["time"] = time;
    replace_keyframes(std::move(keys));
    key_time_ = time;
    set_status(fmt::format("keyframe {} at time {}", at, time));
  });
}

bool ViewerState::update_keyframe(std::size_t index, std::optional<Ease> ease) {
  return guard("keyframe update", [&] {
    check_index(index, keyframes_.size());
    json keys = keyframes_;
    const json& old = keyframes_[index];
    json entry = entry_of(surface_, ease ? *ease : keyframe_ease(index));
    // The entry keeps its own way of placing it: a time, or a frame.
    if (old.contains("frame"))
      entry["frame"] = old["frame"];
    else
      entry["time"] = old["time"];
    keys[index] = std::move(entry);
    replace_keyframes(std::move(keys));
    set_status(fmt::format("keyframe {} updated", index));
  });
}

bool ViewerState::set_keyframe_ease(std::size_t index, Ease ease) {
  return guard("keyframe ease", [&] {
    check_index(index, keyframes_.size());
    json keys = keyframes_;
    keys[index]["ease"] = ease_name(ease);
    replace_keyframes(std::move(keys));
  });
}

bool ViewerState::move_keyframe(std::size_t index, double time) {
  return guard("keyframe move", [&] {
    check_index(index, keyframes_.size());
    check_time(time);
    const int frames = keyframe_frames();
    if (index > 0 && !(entry_time(keyframes_[index - 1], frames) < time))
      throw InvalidArgument(fmt::format(
          "keyframes must stay in increasing time: keyframe {} is at {}, keyframe {} may not "
          "move to {}",
          index - 1, entry_time(keyframes_[index - 1], frames), index, time));
    if (index + 1 < keyframes_.size() && !(time < entry_time(keyframes_[index + 1], frames)))
      throw InvalidArgument(fmt::format(
          "keyframes must stay in increasing time: keyframe {} is at {}, keyframe {} may not "
          "move to {}",
          index + 1, entry_time(keyframes_[index + 1], frames), index, time));
    json keys = keyframes_;
    keys[index].erase("frame");
    keys[index]["time"] = time;
    replace_keyframes(std::move(keys));
  });
}

bool ViewerState::delete_keyframe(std::size_t index) {
  return guard("keyframe delete", [&] {
    check_index(index, keyframes_.size());
    json keys = keyframes_;
    keys.erase(keys.begin() + static_cast<std::ptrdiff_t>(index));
    // Entries given by frame may now be placed in fewer frames: replace_keyframes refuses the
    // deletion when that puts them out of order.
    replace_keyframes(std::move(keys));
    if (keyframes_.empty()) animation_.is_playing = false;
  });
}

void ViewerState::clear_keyframes() {
  keyframes_ = json::array();
  animation_.is_playing = false;
  key_time_ = 0;
}

bool ViewerState::scrub_keyframes(double time) {
  return guard("keyframe time", [&] {
    check_time(time);
    if (keyframes_.empty())
      throw InvalidArgument("there are no keyframes (keyframe add TIME records one)");
    animation_.is_playing = false;
    show_keyframes_at(time);
  });
}

void ViewerState::show_keyframes_at(double time) {
  const Keyframes tracks = keyframe_tracks();
  const Surface at = tracks.at(surface_, time);
  key_time_ = time;
  for (const KeyTrack& t : tracks.params)
    if (!set_parameter(t.name, at.field.parameter_values()[at.field.parameter_index(t.name)]))
      throw detail::ActionFailed{};
  if (!tracks.camera.empty() && !set_camera(at.camera)) throw detail::ActionFailed{};
}

void ViewerState::advance_keyframes(double dt) {
  double t = key_time_ + animation_.direction * animation_.speed * dt;
  if (t >= 1 || t <= 0) {
    const double edge = t >= 1 ? 1 : 0;
    if (animation_.loop) {
      t = std::clamp(2 * edge - t, 0.0, 1.0);  // back the other way from the end
      animation_.direction = -animation_.direction;
    } else {
      t = edge;
      animation_.is_playing = false;
    }
  }
  if (!guard("keyframes", [&] { show_keyframes_at(t); })) animation_.is_playing = false;
}

}  // namespace zeroset::viewer

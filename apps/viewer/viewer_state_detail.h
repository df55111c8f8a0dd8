#pragma once
// What the parts of ViewerState share: the floater job's control block and the signal of a
// failed nested action. Private to the viewer state (viewer_state.cpp, viewer_settings.cpp,
// viewer_camera.cpp, viewer_jobs.cpp, viewer_keyframes.cpp and the command handlers in
// commands.cpp).
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "viewer_state.h"

namespace zeroset::viewer {

// What the UI thread tells the floater job. The job polls it before every step; versions say
// what changed since the job last looked.
struct ViewerState::FloaterControl {
  std::mutex mutex;
  std::condition_variable_any changed;
  Surface surface;                    // the latest surface, parameters included
  std::uint64_t surface_version = 0;  // new equation or clip
  std::uint64_t params_version = 0;   // new parameter values
  FloaterOptions options;
  std::uint64_t options_version = 0;
  std::uint64_t reset_version = 0;
  std::atomic<bool> wants_frame{true};  // the UI took the last frame: post the next one
  // A parameter is being animated: keep stepping even when at rest, since the next value is
  // due any moment (the UI thread sets it once per frame).
  std::atomic<bool> is_animating{false};
};

namespace detail {

/// The singular set for `stats`: singular_set_json (ends of curves only) with the summary, the
/// note, the search's time and whether it reflects the surface as it is now; {} entries empty
/// before the first search.
nlohmann::json singular_json(const SingularFrame* frame, bool is_current);

/// The "animation"/"keyframes" entries of scene settings, an empty array when there are none
/// (viewer_keyframes.cpp).
nlohmann::json scene_keyframes(const nlohmann::json& settings);
/// The frame count that places keyframes given by frame (ViewerState::keyframe_frames).
int keyframe_frames(const nlohmann::json& keys);

/// Thrown by a command whose action failed (and already set the error status); guard() lets
/// it pass without a second message.
struct ActionFailed {};

}  // namespace detail
}  // namespace zeroset::viewer

// The singular set in the viewer: found on a background worker of its own while the overlay is
// on, again whenever the equation, a parameter or the clip changed, and summarised for the
// panel and the `stats` command. The GL view draws it in the floater and mesh modes; the ray
// tracer draws it into the picture (start_preview_job).
#include <fmt/core.h>

#include <chrono>
#include <new>
#include <string>

#include "viewer_state.h"
#include "viewer_state_detail.h"

namespace zeroset::viewer {

using json = nlohmann::json;

SingularFrame find_singular_frame(const Surface& surface, bool substitute_clip,
                                  std::stop_token stop) {
  SingularFrame frame;
  if (!surface.clip.is_bounded()) {
    frame.note =
        "not searched: the search needs a bounded clip (a sphere, or planes closing "
        "a box, under Clip)";
    return frame;
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    frame.set = find_singular_set(surface, {}, stop);
    frame.summary = singular_set_summary(frame.set);
  } catch (const std::bad_alloc&) {
    frame.note = "the search ran out of memory";
  } catch (const std::exception& e) {
    frame.note = fmt::format("the search failed: {}", e.what());
  }
  frame.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  auto add_note = [&](const std::string& text) {
    frame.note += (frame.note.empty() ? "" : " ") + text;
  };
  if (frame.set.has_singular_sheet) {
    const Vec3& p = frame.set.singular_sheet_example;
    add_note(fmt::format(
        "F = G^2 on a sheet through ({:.4g}, {:.4g}, {:.4g}): it is not drawn, and since F "
        "never changes sign there the modes may miss it; look at G instead.",
        p.x(), p.y(), p.z()));
  }
  if (substitute_clip) {
    std::string specs;
    for (const std::string& s : surface.clip.to_specs()) specs += (specs.empty() ? "" : " ") + s;
    add_note(
        fmt::format("The surface has no bounded clip of its own: searched inside {} only.", specs));
  }
  return frame;
}

json detail::singular_json(const SingularFrame* frame, bool is_current) {
  json j = frame ? singular_set_json(frame->set, false) : json::object();
  j["summary"] = frame ? frame->summary : std::string();
  j["note"] = frame ? frame->note : std::string();
  j["seconds"] = frame ? frame->seconds : 0.0;
  j["current"] = is_current;
  return j;
}

std::shared_ptr<const SingularFrame> ViewerState::singular() const {
  return display_.show_singular ? singular_ : nullptr;
}

bool ViewerState::singular_is_current() const {
  return !display_.show_singular || (singular_ && singular_->surface_version == surface_version_);
}

bool ViewerState::update_singular() {
  bool is_new = false;
  if (!display_.show_singular) {
    if (singular_started_ != 0 || singular_) {
      singular_worker_.cancel();
      singular_box_.clear();
      singular_ = nullptr;
      singular_started_ = 0;
      is_new = true;
    }
  } else {
    if (auto f = singular_box_.take(); f && f->surface_version >= singular_floor_) {
      // A sheet where F = G² is what the commands warn about: the log says it when it appears.
      const bool had_sheet = singular_ && singular_->set.has_singular_sheet;
      singular_ = std::move(f);
      is_new = true;
      if (singular_->set.has_singular_sheet && !had_sheet)
        set_status("warning: " + singular_->note);
    }
    // A search that is still running finishes first (its result is one parameter edit old)
    // unless the equation or clip changed: so a moving slider shows a set at every search.
    if (singular_started_ != surface_version_ &&
        (singular_cancel_now_ || singular_worker_.is_idle()))
      start_singular_job();
  }
  singular_cancel_now_ = false;
  // The ray tracer draws the set into its picture: trace again when the set changed.
  if (mode_ == Mode::kRaytrace && preview_ && preview_->generation == generation_ &&
      preview_->singular != singular())
    needs_restart_ = true;
  return is_new;
}

void ViewerState::start_singular_job() {
  const Surface surface = surface_;
  const bool substitute = clip_is_substitute_;
  const std::uint64_t version = surface_version_;
  Mailbox<SingularFrame>* box = &singular_box_;
  singular_started_ = version;
  // submit() cancels a running search through its stop token.
  singular_worker_.submit([=](std::stop_token stop) {
    auto frame = std::make_shared<SingularFrame>(find_singular_frame(surface, substitute, stop));
    if (stop.stop_requested()) return;  // incomplete: a newer search replaces it
    frame->surface_version = version;
    box->post(std::move(frame));
  });
}

}  // namespace zeroset::viewer

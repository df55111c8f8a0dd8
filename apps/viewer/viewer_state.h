#pragma once
// Everything the viewer knows and does, without a window: the surface and its parameters, the
// camera, the animation, the settings of each mode, the background jobs that compute what is
// drawn, and every user action. The GL view and the ImGui panel only read this state and call
// its actions, so tests drive it like a user ("Drive viewer state without a window").
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "job_worker.h"
#include "viewer.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/io/image.h"
#include "zeroset/mesh/carry.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/render.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/scene.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::viewer {

struct CommandLine;

/// The singular set of the surface as one job found it, for the overlay and the panel.
struct SingularFrame {
  SingularSet set;
  std::string summary;  ///< singular_set_summary(set); empty when the search could not run
  /// What the user should know beyond the summary: a singular sheet (F = G²) that is not
  /// drawn, a clip the search cannot use, a failure. Empty when there is nothing to say.
  std::string note;
  double seconds = 0;
  std::uint64_t surface_version = 0;  ///< the surface edit (equation, parameter, clip) it reflects
};

/// The singular set of `surface` for the viewer: find_singular_set, timed and summarised. Never
/// throws: a clip that is not bounded (the search needs one) or a failure of the search becomes
/// the note. `substitute_clip` says the clip is the viewer's stand-in for a surface that came
/// without a bounded one (the note says the set was searched inside it only). When `stop` is
/// requested the result is incomplete.
SingularFrame find_singular_frame(const Surface& surface, bool substitute_clip,
                                  std::stop_token stop = {});

/// One ray-traced preview: the picture at 1/divisor of the viewport's resolution.
struct PreviewFrame {
  Image image;
  int divisor = 1;  ///< 8, 4, 2, then 1 (full resolution)
  RenderStats stats;
  std::uint64_t generation = 0;                   ///< the job it came from
  std::shared_ptr<const SingularFrame> singular;  ///< the singular set drawn into it, if any
};

/// A copy of the floaters after one step, for drawing and saving.
struct FloaterFrame {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;    ///< unit ∇F
  std::vector<double> radii;    ///< σ_i
  StepStats last;               ///< the step that produced this state
  double steps_per_second = 0;  ///< simulation rate over the last half second or so
  double nominal_radius = 0;    ///< σ̂ in use
  std::uint64_t generation = 0;
  std::uint64_t surface_version = 0;  ///< the equation / clip edit it reflects
  std::uint64_t params_version = 0;   ///< the parameter edit it reflects
};

/// The mesh as polygonized, then after each improver step.
struct MeshFrame {
  Mesh mesh;  ///< with unit normals (∇F, face normals where ∇F vanishes)
  PolygonizeStats polygonize;
  CrossingStats crossings;  ///< the sheets joined along singular curves (docs/meshing.md)
  ImproveStats improve;     ///< after the last step (default before the first)
  int improver_steps = 0;   ///< steps applied to `mesh` so far
  bool is_final = false;    ///< no more steps will follow for this generation
  std::uint64_t generation = 0;
  /// What the mesh lies on (its parameter values): a parameter change carries it from here.
  Surface surface;
  /// The mesh settings and surface structure it was made for (ViewerState's mesh_structure_):
  /// only a mesh of the current structure is carried.
  std::uint64_t structure = 0;
  /// The singular curves when the settings leave them out of `mesh` (carrying needs them).
  std::vector<MeshCurve> hidden_curves;
  bool carried = false;      ///< carried from the previous mesh (docs/viewer.md, live meshes)
  double carry_seconds = 0;  ///< the carrying's time
  /// The singular set the carrying found on `surface`: the next carry need not search it again.
  std::optional<CarrySingularSet> singular;
  std::string rebuild_reason;  ///< why carrying failed when it was tried and this was rebuilt
};

/// A parameter animation: the parameter runs through its range at `speed` ranges per second,
/// back and forth when `loop`, else it stops at the end.
struct Animation {
  std::string parameter;  ///< empty: the first parameter of the surface
  bool is_playing = false;
  bool loop = true;
  double speed = 0.1;  ///< fraction of the parameter's range per second
  int direction = 1;   ///< +1 towards max, -1 towards min
};

/// How the GL modes draw.
struct DisplaySettings {
  bool draw_points = false;    ///< floaters as round points instead of oriented disks
  double disk_scale = 0.75;    ///< disk radius = disk_scale·σ_i (as `zeroset sample --png`)
  double point_size_px = 3;    ///< size of a point in pixels
  bool wireframe = false;      ///< mesh: overlay the edges
  bool show_singular = false;  ///< overlay the singular set (every mode)
};

/// Checks disk_scale in (0, 10] and point_size_px in [1, 64]; throws SettingError naming the
/// command ("disk-scale", "point-size").
void validate_display(const DisplaySettings& display);

// The viewer computes live and draws every result while the user watches, so it keeps tighter
// limits than the library's (zeroset sample and zeroset mesh take the library's). They are
// checked after the library's validators, for viewer commands and scene files alike.

/// Most floaters the viewer simulates live (the library takes up to kMaxFloaterCount).
inline constexpr std::size_t kMaxLiveFloaters = 2'000'000;
/// Marching cubes cells for live meshing (the library takes kMinMeshCells to kMaxMeshCells).
inline constexpr int kMinLiveCells = 4;
inline constexpr int kMaxLiveCells = 512;
/// The viewer's mesh settings before a scene or the user changes them.
inline const MeshSettings kLiveMeshDefaults{.cells = 64,
                                            .improve = true,
                                            .max_improve_steps = std::nullopt,
                                            .boundary = BoundaryMode::kConstrained};
/// Improver steps at most when "improve" is auto (each step is drawn).
inline constexpr int kLiveImproveSteps = 200;
/// Improver steps after carrying a mesh to new parameter values (docs/viewer.md, live meshes).
inline constexpr int kCarryImproveSteps = 3;
/// Seconds over which the mesh update rate is counted.
inline constexpr double kMeshRateWindow = 2;

/// Refuses settings beyond the viewer's live limits with SettingError ("max_count", "cells"),
/// saying which limit and that the command line takes more.
void check_live_limits(const FloaterOptions& options);
void check_live_limits(const MeshSettings& settings);

/// A status line: the result of the last action, or a worker's message.
struct StatusLine {
  std::string text;
  bool is_error = false;
};

/// Live figures for the panel, `stats` and --stats-out.
struct ViewerStats {
  Mode mode = Mode::kRaytrace;
  double fps = 0;           ///< frames drawn per second (frames are drawn when something changed)
  double draw_seconds = 0;  ///< wall time of drawing one frame
  // floaters
  std::size_t floater_count = 0;
  std::size_t floater_steps = 0;
  double steps_per_second = 0;
  double median_residual = 0;
  double max_residual = 0;
  bool converged = false;
  double nominal_radius = 0;
  // mesh
  std::size_t mesh_vertices = 0;
  std::size_t mesh_triangles = 0;
  int improver_steps = 0;
  double polygonize_seconds = 0;
  /// Improved meshes shown per second (carried ones, and rebuilds once improved) over the
  /// last kMeshRateWindow seconds, and how many were carried or rebuilt so far.
  double mesh_updates_per_second = 0;
  std::size_t mesh_carried = 0;
  std::size_t mesh_rebuilt = 0;
  std::string mesh_update;  ///< "carried in 12 ms", "rebuilt: <reason>" or "built"
  // ray tracing
  int preview_divisor = 0;  ///< 0: nothing yet
  double preview_seconds = 0;
  bool is_busy = false;  ///< the mode's job has not finished yet
  // the singular set (while the overlay is on)
  bool show_singular = false;
  std::shared_ptr<const SingularFrame> singular;  ///< the latest found, nullptr before the first
  bool singular_is_current = false;               ///< it reflects the surface as it is now

  nlohmann::json to_json() const;
};

/// The viewer's state and actions. Not thread-safe: the UI thread owns it; background jobs
/// only communicate through mailboxes and a control block. Every action goes through guard():
/// an exception becomes an error status line and the action returns false, so no exception
/// crosses the frame loop; on failure the previous state stays (in particular the last good
/// surface stays on screen). A job's error comes back with the next update() as an error
/// status line, and the last good picture stays.
class ViewerState {
 public:
  /// Opens `scene` in `mode` (nullopt: the scene's saved mode, else ray tracing). Applies the
  /// scene's saved viewer settings; throws BadInput naming the JSON entry when they are
  /// malformed. An unbounded clip is replaced by a sphere (with a status line saying so).
  /// `threads` for the background work, 0: all cores for the ray caster and marching cubes,
  /// half of them for the floater simulation. `origin` names the scene in messages (its file).
  /// Throws InvalidArgument when a parameter has no value.
  ViewerState(Scene scene, std::optional<Mode> mode, int threads = 0,
              const std::string& origin = "scene");
  ~ViewerState();
  ViewerState(const ViewerState&) = delete;
  ViewerState& operator=(const ViewerState&) = delete;

  // ---- the guard -----------------------------------------------------------------------------
  /// Runs `body`; an exception becomes the error status "`action`: message". Returns success.
  bool guard(std::string_view action, const std::function<void()>& body);
  /// Receives every status line as it is set (e.g. to print a script log).
  void set_status_sink(std::function<void(const StatusLine&)> sink) { sink_ = std::move(sink); }
  const StatusLine& status() const { return status_; }
  void set_status(std::string text, bool is_error = false);
  /// What the commands warn about the current field over its clip (survey_warning: F vanishes
  /// identically, or is undefined on part of it), or empty. A new warning is also a status
  /// line "warning: ...", so the log has it.
  const std::string& field_warning() const { return field_warning_; }

  // ---- surface -------------------------------------------------------------------------------
  /// Parses `text`; on error the diagnostics (with caret) go to equation_error() and the
  /// current surface stays (equation_text() is `text` either way). Parameters keep their
  /// values and ranges by name; new ones start at 1 with range [0, 2]. The clip and camera
  /// stay.
  bool set_equation(const std::string& text);
  /// Switches to a catalog surface with its defaults and camera.
  bool select_catalog(std::string_view name);
  /// Loads a scene file (surface, camera and saved settings).
  bool load_scene(const std::string& path);
  bool set_parameter(std::string_view name, double value);
  bool set_parameter_range(std::string_view name, double min, double max);
  /// Replaces the clip; it must be bounded.
  bool set_clip(const Clip& clip);
  bool set_clip_specs(const std::vector<std::string>& specs);

  const Surface& surface() const { return surface_; }
  /// The equation as last typed (it may be the rejected one while equation_error() is set).
  const std::string& equation_text() const { return equation_text_; }
  /// Formatted diagnostics of the last rejected equation; empty when the last one was good.
  const std::string& equation_error() const { return equation_error_; }

  // ---- modes, animation, settings ------------------------------------------------------------
  void set_mode(Mode mode);
  Mode mode() const { return mode_; }
  /// Starts the animation of `parameter` (empty: the current or first parameter).
  bool play(std::string_view parameter = {});
  void pause();
  /// Chooses the parameter to animate (keeps playing if it was).
  bool set_animation_parameter(std::string_view parameter);
  void set_loop(bool loop) { animation_.loop = loop; }
  bool set_speed(double ranges_per_second);
  const Animation& animation() const { return animation_; }

  /// Validated as the library does, then within the live limits.
  bool set_floater_options(const FloaterOptions& options);
  const FloaterOptions& floater_options() const { return floater_options_; }
  /// Removes every floater and seeds again.
  void reset_floaters();
  /// Validated as the library does, then within the live limits.
  bool set_mesh_settings(const MeshSettings& settings);
  const MeshSettings& mesh_settings() const { return mesh_settings_; }
  /// Applies `entries`, keys of the scene file's `object` ("floaters" or "mesh") with values
  /// as the scene file has them, read and checked by the scene file's reader (so a bad value is
  /// refused with its words: "ACTION: /floaters/feedback: must lie in [0, 1000]"), then within
  /// the live limits; the mode's job restarts or takes the new options as for the setters
  /// above. `max_steps`, if given, is the mesh's improver step limit (the viewer's own key).
  /// Nothing changes when anything is refused.
  bool set_settings(std::string_view object, const nlohmann::json& entries, std::string_view action,
                    std::optional<int> max_steps = std::nullopt);
  /// The scene file's `object` ("floaters" or "mesh") for the current settings.
  nlohmann::json settings_object(std::string_view object) const;
  bool set_display(const DisplaySettings& display);
  const DisplaySettings& display() const { return display_; }

  /// Lights, materials and background shared by the GL modes and the ray caster.
  const RenderOptions& look() const { return look_; }
  bool set_look(const RenderOptions& look);
  /// Lights follow the camera (directions in camera coordinates) or stay put in the world.
  void set_lights_follow_camera(bool follow);
  bool lights_follow_camera() const;

  // ---- keyframes (viewer_keyframes.cpp) ------------------------------------------------------
  /// The keyframes as the scene file holds them ("animation"/"keyframes", docs/scenes.md), in
  /// increasing time; an empty array when there are none. While there are any, play() follows
  /// them (`speed` animations per second) instead of one parameter.
  const nlohmann::json& keyframes() const { return keyframes_; }
  bool has_keyframes() const { return !keyframes_.empty(); }
  /// Keyframe `index`'s time in [0, 1]; one given by frame is placed as in an animation of
  /// `frames` frames (keyframe_frames() when not given: a pass over every keyframe, so a
  /// caller that asks for many passes it once).
  double keyframe_time(std::size_t index, std::optional<int> frames = std::nullopt) const;
  /// Keyframe `index`'s ease towards the next (in-out when the entry names none).
  Ease keyframe_ease(std::size_t index) const;
  /// The frame count that places keyframes given by frame: `zeroset animate`'s default (60),
  /// or as many as the last such keyframe needs.
  int keyframe_frames() const;
  /// The tracks of the keyframes for the current surface, read as `zeroset animate` reads them.
  /// Throws BadInput naming the entry when they no longer fit the surface (a parameter the
  /// equation lost).
  Keyframes keyframe_tracks() const;
  /// A keyframe at `time` in [0, 1] with every parameter's value and the camera's azimuth,
  /// elevation, distance, roll and field of view as they are now; `ease` (default in-out) leads
  /// to the next one. Refused at the time of an existing keyframe.
  bool add_keyframe(double time, std::optional<Ease> ease = std::nullopt);
  /// Keyframe `index` takes the current parameters and camera (and `ease` when given).
  bool update_keyframe(std::size_t index, std::optional<Ease> ease = std::nullopt);
  bool set_keyframe_ease(std::size_t index, Ease ease);
  /// Moves keyframe `index` to `time`; refused when that leaves the keyframes out of order.
  bool move_keyframe(std::size_t index, double time);
  bool delete_keyframe(std::size_t index);
  void clear_keyframes();
  /// Shows the keyframes at animation time `time` in [0, 1]: their parameters and camera there.
  /// Stops playing.
  bool scrub_keyframes(double time);
  /// The animation time the keyframes were last shown at.
  double keyframe_playhead() const { return key_time_; }

  // ---- camera --------------------------------------------------------------------------------
  /// Sets the size of the 3D view in pixels (the ray caster renders at this size).
  void set_viewport(int width, int height);
  int viewport_width() const { return viewport_w_; }
  int viewport_height() const { return viewport_h_; }
  const Camera& camera() const { return surface_.camera; }
  bool set_camera(const Camera& camera);
  void orbit(double dx_px, double dy_px);
  void pan(double dx_px, double dy_px);
  void zoom(double factor);
  /// Back to the camera the surface came with.
  void reset_view();
  /// The view through the camera at the viewport's size.
  View view() const;

  // ---- files ---------------------------------------------------------------------------------
  bool save_scene(const std::string& path);
  /// The current mesh (mesh mode) as PLY, OBJ, STL or glb, by the file's extension.
  bool save_mesh(const std::string& path);
  /// The current floaters as PLY with normals and radii.
  bool save_floaters(const std::string& path);
  /// The current view as a POV-Ray scene.
  bool save_pov(const std::string& path);
  /// The scene (surface, camera, settings of every mode) as saved by save_scene.
  Scene scene() const;

  // ---- commands ------------------------------------------------------------------------------
  /// Runs one command line of the viewer's command language (docs/viewer.md), e.g.
  /// "param mu 2", "mode mesh", "equation x^2 + y^2 - z^2". Guarded; returns success.
  bool command(std::string_view line);

  // ---- frames --------------------------------------------------------------------------------
  /// Often (at least once per frame) on the UI thread: advances the animation to wall time
  /// `now_s` (seconds), restarts the mode's job when something it depends on changed, and
  /// collects results (live ones at most once per live frame interval). Returns true when
  /// there is something new to draw.
  bool update(double now_s);
  /// Tells the state a frame was drawn at `now_s` and took `seconds` (smoothed), for stats().
  void frame_drawn(double now_s, double seconds);
  /// Live results (floater and improver steps) are taken for drawing at most once per this
  /// many seconds (kept within [1/30, 1/2]; default 1/30). The window lengthens it when
  /// drawing is slow, so that drawing never takes the CPU the simulation needs.
  void set_live_frame_interval(double seconds);
  static constexpr double kMinLiveFrameInterval = 1.0 / 30;
  static constexpr double kMaxLiveFrameInterval = 0.5;
  /// The mode's work is finished: full-resolution preview, mesh improved (or improvement
  /// off), floaters converged.
  bool is_settled() const;

  std::shared_ptr<const PreviewFrame> preview() const { return preview_; }
  std::shared_ptr<const FloaterFrame> floaters() const { return floaters_; }
  std::shared_ptr<const MeshFrame> mesh() const { return mesh_; }
  /// The singular set to overlay: nullptr while the overlay is off or before the first search
  /// finished. While parameters move it may lag the surface by one search; after a new
  /// equation or clip it is nullptr until the new search finishes.
  std::shared_ptr<const SingularFrame> singular() const;
  /// The overlay is off, or singular() reflects the surface as it is now.
  bool singular_is_current() const;
  ViewerStats stats() const;

 private:
  struct FloaterControl;

  void apply_settings(const nlohmann::json& settings, const std::string& origin);
  nlohmann::json settings() const;
  void open_scene(Scene scene, const std::string& origin);
  void ensure_bounded_clip();
  /// Publishes the surface to the floater job: `structure` for a new equation or clip
  /// (FloaterSystem::set_surface), else new parameter values.
  void surface_changed(bool structure);
  /// The commands' survey of the field (survey_warning), said once when its warning changes.
  void survey_now();
  /// Surveys new parameter values once they rested kSurveyRest, or kSurveyInterval after the
  /// last survey while they keep moving.
  void survey_if_due(double now_s);
  static constexpr double kSurveyRest = 0.25;
  static constexpr double kSurveyInterval = 1;
  /// Before a parametric clip changes size with the parameters: moves the camera (and the home
  /// camera) with it, keeping the view direction and scaling the distance and the target's
  /// offset from the clip's centre by the change of the clip's bounding radius.
  void follow_clip(const Clip& next);
  void advance_animation(double dt);
  /// advance_animation while there are keyframes (viewer_keyframes.cpp).
  void advance_keyframes(double dt);
  /// Sets the parameters and camera to the keyframes' at `time` (no guard).
  void show_keyframes_at(double time);
  /// Validates `keys` as the scene's keyframes for the current surface, then keeps them.
  void replace_keyframes(nlohmann::json keys);
  void restart_job();
  void start_preview_job();
  void start_floater_job();
  void start_mesh_job();
  bool collect_results(double now_s);
  // Counts a mesh frame taken for drawing: carried, rebuilt, improved (for stats()).
  void count_mesh_update(const MeshFrame& m, double now_s);
  void restart_if_needed();
  /// The singular set's job: collects its result and starts it again when the surface changed
  /// (viewer_singular.cpp). Returns true when there is something new to draw.
  bool update_singular();
  void start_singular_job();
  int floater_threads() const;

  // what is shown
  Surface surface_;
  Camera home_camera_;
  std::string equation_text_;
  std::string equation_error_;
  nlohmann::json extra_settings_ = nlohmann::json::object();  // scene keys we keep as they are
  Mode mode_ = Mode::kRaytrace;
  Animation animation_;
  nlohmann::json keyframes_ = nlohmann::json::array();  // the scene file's entries, as they are
  double key_time_ = 0;  // where the keyframes were last shown, in [0, 1]
  FloaterOptions floater_options_;
  MeshSettings mesh_settings_ = kLiveMeshDefaults;
  DisplaySettings display_;
  RenderOptions look_;
  int threads_ = 0;
  int viewport_w_ = 800;
  int viewport_h_ = 800;
  bool clip_is_substitute_ = false;    // ensure_bounded_clip chose the clip, the surface had none
  std::uint64_t surface_version_ = 0;  // counts surface edits (equation, parameter, clip)

  // status
  StatusLine status_;
  std::function<void(const StatusLine&)> sink_;
  std::string field_warning_;
  bool survey_pending_ = false;  // parameters changed since the last survey
  double last_param_change_s_ = -1e9;
  double last_survey_s_ = -1e9;

  // timing
  double last_update_s_ = -1;
  double last_frame_s_ = -1;
  double last_live_frame_s_ = -1e9;
  double live_frame_interval_s_ = kMinLiveFrameInterval;
  double fps_ = 0;
  double draw_seconds_ = 0;

  // what changed since the job started
  bool needs_restart_ = true;  // anything the current job depends on changed
  // Restart at once (mode, catalog, scene, equation, mesh settings); other changes (camera,
  // parameters, clip, look) let the running job show its first result before it is replaced.
  bool cancel_now_ = false;
  bool fresh_floaters_ = true;  // floaters: start a new system (new seeding)

  // background work
  std::uint64_t generation_ = 0;  // of the job currently wanted
  std::shared_ptr<FloaterControl> floater_control_;
  Mailbox<PreviewFrame> preview_box_;
  Mailbox<FloaterFrame> floater_box_;
  Mailbox<MeshFrame> mesh_box_;
  std::shared_ptr<std::atomic<bool>> mesh_wants_frame_ = std::make_shared<std::atomic<bool>>(true);
  std::shared_ptr<const PreviewFrame> preview_;
  std::shared_ptr<const FloaterFrame> floaters_;
  std::shared_ptr<const MeshFrame> mesh_;
  // Counts changes a mesh cannot be carried across (equation, clip spec, mesh settings, mode).
  std::uint64_t mesh_structure_ = 0;
  std::size_t mesh_carried_ = 0, mesh_rebuilt_ = 0;
  std::vector<double> mesh_update_times_;  // when improved meshes were shown, the last window
  // The singular set runs on its own worker beside the mode's job (the floater job never
  // ends). Parameter edits let a running search finish (its result lags by one edit) and
  // start the next with the newest values; a new equation or clip cancels it at once.
  Mailbox<SingularFrame> singular_box_;
  std::shared_ptr<const SingularFrame> singular_;
  std::uint64_t singular_started_ = 0;  // surface version of the last search started, 0: none
  std::uint64_t singular_floor_ = 0;    // results of older versions belong to another surface
  bool singular_cancel_now_ = false;
  JobWorker worker_;  // last: its thread stops before the mailboxes it writes go away
  JobWorker singular_worker_;
};

}  // namespace zeroset::viewer

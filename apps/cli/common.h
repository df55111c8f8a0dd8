#pragma once
// Shared pieces of the `zeroset` subcommands: the SURFACE argument, --param/--clip,
// progress bars, --stats files. Every subcommand registers itself through one function.
#include <CLI/CLI.hpp>
#include <functional>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/surface/field_survey.h"
#include "zeroset/surface/scene.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::cli {

/// The SURFACE positional argument with --param and --clip, as every stage takes them.
struct SurfaceArgs {
  std::string spec;
  std::vector<std::string> params;  // "k=v"
  std::vector<std::string> clips;   // clip specs
  /// Adds SURFACE (required unless `optional`), --param and --clip to `cmd`.
  void add_to(CLI::App* cmd, bool optional = false);
  /// The overrides from --param and --clip (throws InvalidArgument on malformed ones).
  SurfaceOverrides overrides() const;
  /// Resolves the surface (catalog name, scene file or equation) with the overrides.
  Scene resolve() const;
};

/// Parses "name=value" (value a finite number). Throws InvalidArgument saying which and why.
std::pair<std::string, double> parse_assignment(const std::string& text, const std::string& flag);
/// Adds --param NAME=VALUE to `o`; a parameter given twice is an InvalidArgument naming it
/// (`text` is the flag's whole value).
void add_parameter_override(SurfaceOverrides& o, const std::string& name, double value,
                            const std::string& flag, const std::string& text);
/// Parses "name=a:b" (a parameter's range, both ends within check_parameter_value's limit).
/// Throws InvalidArgument.
struct ParamRange {
  std::string name;
  double from = 0, to = 0;
};
ParamRange parse_range(const std::string& text, const std::string& flag);
/// The frames an animation run renders: first..last, both included, 0-based as the frames'
/// file names (frame_0000.png is frame 0).
struct FrameRange {
  int first = 0, last = 0;
  int count() const { return last - first + 1; }
};
/// Parses --frame-range "A-B" (or "A", one frame) for an animation of `frames` frames (1 to
/// kMaxFrames): whole numbers with 0 ≤ A ≤ B < frames. Empty `text`: every frame. Throws
/// InvalidArgument.
FrameRange parse_frame_range(const std::string& text, int frames, const std::string& flag);
/// The most frames an animation (animate, export --animate) or a viewer run may have.
inline constexpr int kMaxFrames = 1'000'000;
/// The most floater steps a run may ask for (the viewer's `steps` command has the same limit).
inline constexpr double kMaxFloaterSteps = 1e8;
/// Throws InvalidArgument naming `flag` unless lo ≤ value ≤ hi (NaN never is): the check of
/// a numeric flag that no settings validator covers.
void check_flag_range(const std::string& flag, double value, double lo, double hi);
/// Parses "WxH" (whole numbers within validate_image_size's limits). Throws InvalidArgument.
std::pair<int, int> parse_size(const std::string& text, const std::string& flag);

/// Which flag sets each key of a settings object, e.g. {"max_count", "--max-count"}.
using FlagNames = std::initializer_list<std::pair<std::string_view, std::string_view>>;
/// Runs a settings validator on what the flags set; its SettingError becomes InvalidArgument
/// naming the flag that sets the key (the key itself when no flag does), with the validator's
/// words, so a flag and a scene file's entry are refused alike.
void validate_flags(const std::function<void()>& validate, FlagNames flags);
/// The flag `flags` gives for a setting's key (the key itself when it has none).
std::string flag_name(FlagNames flags, std::string_view key);

/// Comma-separated finite numbers ("1,2.5,-3"); InvalidArgument naming `flag` otherwise.
std::vector<double> parse_numbers(const std::string& text, const std::string& flag);

/// `camera` with --camera AZIMUTH,ELEVATION[,DISTANCE[,ROLL]] applied (nothing when `spec` is
/// empty; a missing ROLL is 0), checked by validate_camera with the flag's name in the message.
Camera with_camera_flag(Camera camera, const std::string& spec);
/// `camera` with --projection perspective|ortho[:HEIGHT] applied (nothing when `spec` is
/// empty): ortho without a HEIGHT fits the clip volume; checked by validate_camera.
Camera with_projection_flag(Camera camera, const std::string& spec);

/// A progress bar on stderr; silent when stderr is not a terminal or --quiet was given.
class Progress {
 public:
  Progress(std::string label, bool quiet);
  ~Progress();
  void update(double fraction);  ///< thread-safe enough: called from one thread at a time
  void finish();

 private:
  std::string label_;
  bool enabled_;
  int last_permille_ = -1;
};

/// Writes a JSON document atomically (pretty-printed).
void write_json(const nlohmann::json& j, const std::string& path);

/// Adds --show-singular (draw the singular set over the pictures) to `cmd`, setting `flag`;
/// `pictures` names what it draws on ("the picture", "the --png picture").
void add_show_singular_flag(CLI::App* cmd, bool& flag, const std::string& pictures);
/// The "singular_set" entry of a --stats file: the set without its polylines, or null when it
/// was not searched.
nlohmann::json singular_stats(const std::optional<SingularSet>& set);

/// Global flags every subcommand sees.
struct GlobalFlags {
  bool quiet = false;
  int threads = 0;  // 0: all cores
};
GlobalFlags& global_flags();

/// Prints a line to stdout unless --quiet.
void say(const std::string& line);
/// Prints "zeroset: warning: LINE" to stderr unless --quiet.
void warn(const std::string& line);

/// Warns when ∇F vanishes on a whole sheet of F = 0 (F = G²): marching cubes sees no sign change
/// there and floaters settle on a surface where the normal is undefined. Uses `known` when given,
/// else a quick search on a coarse grid (bounded clips only).
void warn_if_singular_sheet(const Surface& surface, const std::optional<SingularSet>& known);

/// Surveys F over the clip (survey_field) and warns once when F vanishes identically or is
/// undefined (NaN or infinite) on part of the clip (survey_warning). Every stage command
/// calls it once, so they all say the same.
FieldSurvey survey_and_warn(const Surface& surface);

void register_catalog_commands(CLI::App& app);    // list, info, eval
void register_render_commands(CLI::App& app);     // render, animate, export
void register_sample_command(CLI::App& app);      // sample
void register_mesh_command(CLI::App& app);        // mesh
void register_view_command(CLI::App& app);        // view
void register_completion_command(CLI::App& app);  // completion

}  // namespace zeroset::cli

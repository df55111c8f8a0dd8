#pragma once
// Scripts: a file of viewer commands (commands.h) run one after the other, with frame-loop
// commands (frames, wait, steps, sleep, screenshot, ...) that let frames pass in between. Tests
// and documentation pictures drive the viewer through them like a user would.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "commands.h"

namespace zeroset::viewer {

class ViewerState;

/// What a script needs from the window.
class ScriptHost {
 public:
  virtual ~ScriptHost() = default;
  /// Saves the frame just drawn as PNG. Throws IoError.
  virtual void save_screenshot(const std::string& path) = 0;
  virtual void set_ui_visible(bool visible) = 0;
  /// One line of the script log (commands, statistics, errors).
  virtual void print(const std::string& line) = 0;
};

/// A parsed script and how far it has run. Not thread-safe (the UI thread runs it).
class Script {
 public:
  /// The longest script file read (16 MiB: a few hundred thousand commands); a longer one, or
  /// a device such as /dev/zero, is refused before it fills memory.
  static constexpr std::size_t kMaxScriptBytes = std::size_t{16} << 20;
  /// Parses and checks every line (command names and argument counts) before anything runs.
  /// Throws InvalidArgument "ORIGIN:LINE: ..." for the first bad line.
  static Script parse(std::string_view text, const std::string& origin);
  /// Reads and parses a file. Throws IoError, or BadInput for a bad line or a file longer
  /// than kMaxScriptBytes.
  static Script load(const std::string& path);

  /// Called once per frame, after the frame was drawn: runs commands until one needs more
  /// frames to pass (or the script ends). `now_s` is the wall time in seconds.
  void advance(ViewerState& state, ScriptHost& host, double now_s);
  bool is_finished() const { return is_finished_; }
  /// False while the script only waits for time to pass or for the state (sleep, wait,
  /// steps): frames need not be drawn for it then.
  bool needs_frames() const {
    return !is_finished_ && (wait_ == Wait::kNone || wait_ == Wait::kFrames);
  }
  /// Commands that failed without a following `expect-error`, and waits that timed out.
  int failures() const { return failures_; }

 private:
  struct Line {
    int number = 0;
    std::string text;
    CommandLine command;
  };
  enum class Wait { kNone, kFrames, kSettled, kSteps, kTime };

  bool waiting(ViewerState& state, ScriptHost& host, double now_s);
  void run(const Line& line, ViewerState& state, ScriptHost& host, double now_s);
  void fail(const Line& line, ScriptHost& host, const std::string& message);
  void settle_pending_failure(ScriptHost& host);

  std::string origin_;
  std::vector<Line> lines_;
  size_t next_ = 0;
  bool is_finished_ = false;
  int failures_ = 0;
  double start_s_ = -1;
  // The frame loop command in progress.
  Wait wait_ = Wait::kNone;
  const Line* wait_line_ = nullptr;
  long long frames_left_ = 0;
  double deadline_s_ = 0;
  std::size_t steps_target_ = 0;
  // The last command failed with this message (until expect-error or the next command).
  bool has_pending_failure_ = false;
  int pending_line_ = 0;
  std::string pending_message_;
};

}  // namespace zeroset::viewer

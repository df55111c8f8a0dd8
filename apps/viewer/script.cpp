#include "script.h"

#include <fmt/core.h>

#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset::viewer {
namespace {

// How long `wait` and `steps` wait at most unless told otherwise.
constexpr double kDefaultTimeoutS = 60;

// Checks the numbers of a frame-loop command; returns them (empty for other commands).
std::vector<double> frame_loop_numbers(const CommandLine& c) {
  std::vector<double> out;
  if (c.name == "frames") {
    out.push_back(static_cast<double>(parse_integer(c.args[0], "frames", 0, 1'000'000)));
  } else if (c.name == "wait" || c.name == "sleep") {
    if (!c.args.empty()) {
      const double s = parse_number(c.args[0], c.name + " seconds");
      if (!(s >= 0 && s <= 3600))
        throw InvalidArgument(c.name + " seconds", c.args[0], "must lie in [0, 3600]");
      out.push_back(s);
    }
  } else if (c.name == "steps") {
    out.push_back(static_cast<double>(parse_integer(c.args[0], "steps", 0, 100'000'000)));
    if (c.args.size() == 2) {
      const double s = parse_number(c.args[1], "steps seconds");
      if (!(s >= 0 && s <= 3600))
        throw InvalidArgument("steps seconds", c.args[1], "must lie in [0, 3600]");
      out.push_back(s);
    }
  } else if (c.name == "ui") {
    out.push_back(parse_on_off(c.args[0], "ui") ? 1 : 0);
  }
  return out;
}

}  // namespace

Script Script::parse(std::string_view text, const std::string& origin) {
  Script script;
  script.origin_ = origin;
  int number = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view raw = text.substr(pos, eol - pos);
    if (!raw.empty() && raw.back() == '\r') raw.remove_suffix(1);
    ++number;
    pos = eol + 1;
    CommandLine c = split_command(raw);
    if (c.is_empty()) continue;
    try {
      const CommandInfo& info = check_command(c);
      if (info.is_frame_loop()) frame_loop_numbers(c);
      if (c.name == "mode") parse_mode(c.args[0]);
    } catch (const BadInput& e) {
      throw InvalidArgument(fmt::format("{}:{}: {}", origin, number, e.what()));
    }
    script.lines_.push_back({number, std::string(raw), std::move(c)});
  }
  return script;
}

Script Script::load(const std::string& path) {
  return parse(read_text_file(path, kMaxScriptBytes, "a viewer script"), path);
}

void Script::advance(ViewerState& state, ScriptHost& host, double now_s) {
  if (start_s_ < 0) start_s_ = now_s;
  if (is_finished_) return;
  if (wait_ != Wait::kNone && waiting(state, host, now_s)) return;
  wait_ = Wait::kNone;
  // A screenshot shows the frame drawn after every earlier command took effect.
  bool changed_since_frame = false;
  while (next_ < lines_.size()) {
    const Line& line = lines_[next_];
    if (line.command.name == "screenshot" && changed_since_frame) return;
    ++next_;
    run(line, state, host, now_s);
    if (wait_ != Wait::kNone || is_finished_) return;
    const CommandInfo* info = find_command(line.command.name);
    changed_since_frame =
        changed_since_frame || !info->is_frame_loop() || line.command.name == "ui";
  }
  settle_pending_failure(host);
  is_finished_ = true;
}

bool Script::waiting(ViewerState& state, ScriptHost& host, double now_s) {
  switch (wait_) {
    case Wait::kNone:
      return false;
    case Wait::kFrames:
      return --frames_left_ > 0;
    case Wait::kTime:
      return now_s < deadline_s_;
    case Wait::kSettled:
      if (state.is_settled()) return false;
      if (now_s < deadline_s_) return true;
      fail(*wait_line_, host, "the view did not settle in time");
      return false;
    case Wait::kSteps:
      // The singular set, when shown, is part of the picture the steps lead to.
      if (state.stats().floater_steps >= steps_target_ && state.singular_is_current()) return false;
      if (now_s < deadline_s_) return true;
      fail(*wait_line_, host,
           state.stats().floater_steps >= steps_target_
               ? std::string("the singular set was not found in time")
               : fmt::format("the floaters reached {} of {} steps in time",
                             state.stats().floater_steps, steps_target_));
      return false;
  }
  return false;
}

void Script::run(const Line& line, ViewerState& state, ScriptHost& host, double now_s) {
  const CommandLine& c = line.command;
  if (c.name == "expect-error") {
    if (!has_pending_failure_)
      fail(line, host, "the previous command did not fail");
    else if (!c.rest.empty() && pending_message_.find(c.rest) == std::string::npos)
      fail(line, host,
           fmt::format("the previous command failed, but its message does not "
                       "contain '{}': {}",
                       c.rest, pending_message_));
    else
      host.print(fmt::format("{}:{}: failed as expected", origin_, line.number));
    has_pending_failure_ = false;
    return;
  }
  settle_pending_failure(host);
  host.print(fmt::format("{}:{}: {}", origin_, line.number, line.text));
  const std::vector<double> numbers = frame_loop_numbers(c);
  wait_line_ = &line;
  if (c.name == "frames") {
    frames_left_ = static_cast<long long>(numbers[0]);
    if (frames_left_ > 0) wait_ = Wait::kFrames;
  } else if (c.name == "wait") {
    deadline_s_ = now_s + (numbers.empty() ? kDefaultTimeoutS : numbers[0]);
    wait_ = Wait::kSettled;
  } else if (c.name == "steps") {
    if (state.mode() != Mode::kFloaters) {
      fail(line, host, "'steps' needs floaters mode");
      return;
    }
    steps_target_ = state.stats().floater_steps + static_cast<std::size_t>(numbers[0]);
    deadline_s_ = now_s + (numbers.size() > 1 ? numbers[1] : kDefaultTimeoutS);
    wait_ = Wait::kSteps;
  } else if (c.name == "sleep") {
    deadline_s_ = now_s + numbers[0];
    wait_ = Wait::kTime;
  } else if (c.name == "screenshot") {
    if (!state.guard("screenshot", [&] { host.save_screenshot(c.args[0]); })) {
      has_pending_failure_ = true;
      pending_line_ = line.number;
      pending_message_ = state.status().text;
    }
  } else if (c.name == "ui") {
    host.set_ui_visible(numbers[0] != 0);
  } else if (c.name == "stats") {
    nlohmann::json j = state.stats().to_json();
    j["time_s"] = now_s - start_s_;
    host.print(j.dump());
  } else if (c.name == "quit") {
    is_finished_ = true;
  } else if (!state.command(line.text)) {
    has_pending_failure_ = true;
    pending_line_ = line.number;
    pending_message_ = state.status().text;
  }
}

void Script::fail(const Line& line, ScriptHost& host, const std::string& message) {
  ++failures_;
  host.print(fmt::format("{}:{}: error: {}", origin_, line.number, message));
}

void Script::settle_pending_failure(ScriptHost& host) {
  if (!has_pending_failure_) return;
  has_pending_failure_ = false;
  ++failures_;
  host.print(fmt::format("{}:{}: error: {}", origin_, pending_line_, pending_message_));
}

}  // namespace zeroset::viewer

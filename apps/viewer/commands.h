#pragma once
// The viewer's command language: one command per line, words separated by blanks, `#` starts
// a comment. Scripts (--script) and the panel's command field use it; docs/viewer.md lists
// every command. State commands run through ViewerState::command; frame-loop commands
// (frames, wait, screenshot, ...) are the script runner's.
#include <string>
#include <string_view>
#include <vector>

namespace zeroset::viewer {

class ViewerState;
struct CommandLine;

/// Runs a state command on the viewer (its arguments already counted by check_command).
/// Throws on bad arguments; a failed action has already set the error status.
using CommandHandler = void (*)(ViewerState& state, const CommandLine& command);

struct CommandInfo {
  std::string_view name;
  int min_args = 0;
  int max_args = 0;        ///< -1: any number (the rest of the line)
  std::string_view usage;  ///< e.g. "param NAME VALUE"
  std::string_view help;   ///< one line
  /// What the command does to the viewer state; nullptr for a command that needs the
  /// window's frame loop (the script runner handles those).
  CommandHandler run = nullptr;
  bool is_frame_loop() const { return run == nullptr; }
};

/// Every command, in the order docs/viewer.md lists them, each with its handler.
const std::vector<CommandInfo>& command_table();
/// The command with that name, or nullptr.
const CommandInfo* find_command(std::string_view name);

/// A command line split into its name and arguments. `rest` is the text after the name with
/// surrounding blanks removed (the equation of `equation`, which may contain blanks).
struct CommandLine {
  std::string name;
  std::vector<std::string> args;
  std::string rest;
  bool is_empty() const { return name.empty(); }
};

/// Splits a line; comments and blank lines give an empty CommandLine.
CommandLine split_command(std::string_view line);
/// Checks the name and the argument count; throws InvalidArgument with the usage.
const CommandInfo& check_command(const CommandLine& command);

/// "on"/"off" (also true/false, yes/no, 1/0); throws InvalidArgument naming `what`.
bool parse_on_off(std::string_view text, std::string_view what);
/// A finite number; throws InvalidArgument naming `what`.
double parse_number(std::string_view text, std::string_view what);
/// A whole number in [lo, hi]; throws InvalidArgument naming `what`.
long long parse_integer(std::string_view text, std::string_view what, long long lo, long long hi);

}  // namespace zeroset::viewer

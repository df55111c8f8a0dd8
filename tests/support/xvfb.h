#pragma once
// Runs `zeroset view` in a virtual X server (xvfb-run) with Mesa's software OpenGL.
//
// Each run gets its own X authority file (`xvfb-run -f`), so xvfb-run makes no temporary
// directory of its own: removing that directory at exit sometimes failed, and xvfb-run then
// replaced the viewer's exit code with its own (5).
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/run_command.h"

namespace zeroset::test {

inline bool has_xvfb() { return std::system("command -v xvfb-run > /dev/null 2>&1") == 0; }

/// `binary view ARGS` on a virtual screen of `screen` ("WxH"), 24 bits deep.
inline CommandResult run_viewer(const std::string& binary, const std::string& args,
                                const std::string& screen) {
  static std::atomic<int> counter{0};
  const auto dir = std::filesystem::temp_directory_path() / "zeroset_xauth";
  std::filesystem::create_directories(dir);
  const auto auth = dir / (std::to_string(::getpid()) + "-" + std::to_string(counter++));
  CommandResult r = run_command("LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -f " + auth.string() +
                                " -s '-screen 0 " + screen + "x24' " + binary + " view " + args);
  std::error_code ec;
  std::filesystem::remove(auth, ec);
  return r;
}

}  // namespace zeroset::test

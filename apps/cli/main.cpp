// zeroset: make implicit surfaces F(x, y, z; q) = 0 visible.
#include <fmt/core.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <string_view>
#if defined(__linux__)
#include <unistd.h>
#endif

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/io/output_transaction.h"

namespace {

// OpenMP's default wait policy keeps idle workers spinning at every barrier for a while
// (libgomp: 300,000 spins). On a machine with other work running (the usual desktop) that
// steals the core the busy worker needs: zeroset's coarse-grained parallel loops then ran
// several times slower than on one thread. Waiting passively instead costs a wake-up at every
// barrier, 60 to 100 µs on a virtual machine: a tenth of a floater step at 10,000 floaters.
// So workers spin briefly and then sleep (libgomp: 10,000 spins, a few tens of µs; passive
// waiting with another OpenMP runtime). Measured on 2 cores, `sample kummer --max-count 20000
// --steps 300`: 0.65 s against 0.96 to 2.05 s passive when idle, the same (2.4 to 2.9 s) with a
// busy process beside it. The runtime reads the policy when it loads, before main, so the
// process executes itself once more with it, unless the user chose one. Only the commands
// whose work runs in OpenMP loops pay for that (the renderer has its own threads).
void choose_openmp_waiting(int argc, char** argv) {
#if defined(__linux__)
  if (std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr) return;
  const auto uses_openmp = [](std::string_view a) {
    return a == "mesh" || a == "sample" || a == "view";
  };
  if (std::none_of(argv + 1, argv + argc, [&](const char* a) { return uses_openmp(a); })) return;
#if defined(__GNUC__) && !defined(__clang__)
  if (setenv("GOMP_SPINCOUNT", "10000", 1) != 0) return;
#else
  if (setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0) return;
#endif
  execv("/proc/self/exe", argv);  // returns only when it failed: run on as we are
#else
  (void)argc, (void)argv;
#endif
}

/// Prints an error on stderr. fmt::print would throw when stderr itself cannot be written (a
/// full disk behind it too); the message is then lost, but the exit code still tells.
void print_error(const std::string& message) {
  std::fputs(("zeroset: error: " + message + "\n").c_str(), stderr);
}

/// 0 when everything printed on standard output reached it; else 1 with a message: a full
/// disk or device behind it (`zeroset list > /dev/full`) is a failure, not a success.
int standard_output_status() {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int err = errno;
  if (flushed && !std::ferror(stdout) && std::cout.good()) return 0;
  print_error("writing standard output failed" +
              (err != 0 ? ": " + std::string(std::strerror(err)) : std::string()));
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace zeroset;
  choose_openmp_waiting(argc, argv);
  // Ctrl-C or a scheduler's SIGTERM during a long run leaves no temp file behind.
  remove_pending_outputs_on_signals();
  CLI::App app{
      "zeroset — make implicit surfaces F(x, y, z; q) = 0 visible, singular points and\n"
      "self-intersections included.\n\n"
      "SURFACE is a catalog name (see `zeroset list`), an equation in quotes such as\n"
      "\"x^2 + y^2 = z^2\", or a scene file (.json). Free names in an equation are\n"
      "parameters: give them with --param name=value.\n\n"
      "Examples:\n"
      "  zeroset list\n"
      "  zeroset info kummer --param mu=1.5\n"
      "  zeroset eval \"x^2 + y^2 - z^2\" --at 1,0,1\n"
      "  zeroset render kummer -o kummer.png\n"
      "  zeroset sample cone --png cone.png -o cone.ply\n"
      "  zeroset mesh kummer --param mu=1.5 -o kummer.obj\n"
      "  zeroset view kummer\n\n"
      "Exit codes: 0 success, 2 bad input, 1 failure.",
      "zeroset"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "zeroset 0.1.0");
  auto& g = cli::global_flags();
  app.add_flag("-q,--quiet", g.quiet, "Print nothing but errors")->configurable(false);
  app.add_option("--threads", g.threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, zeroset::kMaxThreads));

  cli::register_catalog_commands(app);
  cli::register_render_commands(app);
  cli::register_sample_command(app);
  cli::register_mesh_command(app);
  cli::register_view_command(app);
  cli::register_completion_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Same form as every other error, and a pointer to the help of the command at fault.
    const auto commands = app.get_subcommands();
    const std::string help = commands.empty()
                                 ? "zeroset --help"
                                 : fmt::format("zeroset {} --help", commands.front()->get_name());
    print_error(fmt::format("{}\nSee `{}` for the usage.", e.what(), help));
    return 2;
  } catch (const BadInput& e) {
    print_error(e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    print_error("out of memory");
    return 1;
  } catch (const std::exception& e) {
    print_error(e.what());
    return 1;
  }
  return standard_output_status();
}

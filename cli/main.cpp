// lodkit: one binary, one subcommand per job. main() only parses, dispatches and turns errors into
// exit codes: 0 success, 1 a lodkit::Error (bad input, failed write), 2 a usage error.
#include <lodkit/error.h>
#include <lodkit/io.h>
#include <lodkit/version.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <new>

#include "common.h"

namespace {

// Interrupted (Ctrl-C, kill, a closed terminal): the files being written are removed, then the signal
// takes its default course, so the exit status still says what stopped the run. Without this a hidden
// temporary file, hundreds of MB for a large terrain, was left beside each output.
extern "C" void remove_unfinished_outputs_and_stop(int signal) {
  lodkit::remove_unfinished_outputs();
  std::raise(signal);  // (SA_RESETHAND restored the default action)
}

void clean_up_when_interrupted() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction previous{};
    if (sigaction(signal, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;  // (nohup)
    struct sigaction action{};
    action.sa_handler = remove_unfinished_outputs_and_stop;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(signal, &action, nullptr);
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace lodkit::cli;
  clean_up_when_interrupted();
  CLI::App app{"lodkit " LODKIT_VERSION_STRING
               ": mesh processing and level of detail",
               "lodkit"};
  app.set_version_flag("--version", LODKIT_VERSION_STRING);
  app.require_subcommand(1);
  app.fallthrough();
  GlobalOptions global;
  app.add_flag("-q,--quiet", global.quiet, "No summary or progress on stderr");
  app.footer(R"(Examples:
  lodkit generate torus -o torus.ply --tolerance 0.001
  lodkit info torus.ply --json
  lodkit convert torus.ply torus.drc --quantize 14
  lodkit simplify bunny.ply -o bunny_small.ply --ratio 0.1 --measure
  lodkit compare bunny.ply bunny_small.ply
  lodkit terrain -o mountain.ply --levels 8 --colour
Run 'lodkit <command> --help' for a command's options. Docs: docs/commands/.)");

  std::vector<Command> commands{add_info_command(app, global), add_convert_command(app, global),
                                add_generate_command(app, global),
                                add_simplify_command(app, global), add_compare_command(app, global),
                                add_csg_command(app, global), add_pm_command(app, global),
                                add_terrain_command(app, global), add_subdivide_command(app, global)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (const Command& c : commands)
      if (c.app->parsed()) return c.run();
    return 2;
  } catch (const lodkit::Error& e) {
    std::fprintf(stderr, "lodkit: error: %s\n", e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "lodkit: error: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lodkit: error: %s\n", e.what());
  }
  return 1;
}

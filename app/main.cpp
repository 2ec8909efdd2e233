// springy: the command line.
#include <CLI/CLI.hpp>
#include <iostream>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "sim/error.h"

namespace {

void addRunOverrides(CLI::App* cmd, springy::RunOverrides& o) {
  cmd->add_option("--integrator", o.integrator,
                  "Override the scene's integrator: " + springy::integratorNames());
  cmd->add_option("--dt", o.dt, "Override the scene's time step [s]");
  cmd->add_option("--substeps", o.substeps, "Steps of dt/N per dt");
  cmd->add_option("--duration", o.duration, "Override the simulated duration [s]");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"springy: soft bodies as springy meshes, simulated and rendered offscreen"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "springy 0.1");

  springy::CheckOptions check;
  CLI::App* checkCmd = app.add_subcommand("check", "Run scenes headlessly and check stability; per-body report");
  checkCmd->add_option("scenes", check.scenes, "Scene files (.toml)")->required()->check(CLI::ExistingFile);
  addRunOverrides(checkCmd, check.overrides);
  checkCmd->add_option("--trace", check.trace, "Write per-frame centroid, volume and energies as CSV");

  CLI11_PARSE(app, argc, argv);
  springy::installInterruptHandler();
  try {
    if (checkCmd->parsed()) return springy::runCheck(check);
  } catch (const springy::Error& e) {
    std::cerr << "springy: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

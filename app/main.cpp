// springy: the command line.
#include <iostream>

#include "app/atomic_file.h"
#include "app/cli.h"
#include "sim/error.h"

int main(int argc, char** argv) {
  springy::CommandLine cli;
  springy::installInterruptHandler();
  try {
    cli.args.assign(argv + 1, argv + argc);
    cli.app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.app.exit(e);
  }
  try {
    return cli.dispatch();
  } catch (const springy::Error& e) {
    std::cerr << "springy: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "springy: out of memory (the scene or its meshes are too large for this machine)\n";
    return 1;
  } catch (const std::exception& e) {
    // Not a user error springy foresaw (those are springy::Error): still a message and a clean
    // exit, never std::terminate's abort, so that temporary outputs are removed.
    std::cerr << "springy: unexpected error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

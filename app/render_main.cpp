// springy-render: springy with the drawing commands (app/cli.h DrawingCommands), which springy
// runs for render, frames and report.
#include "app/cli.h"

int main(int argc, char** argv) {
  springy::drawingCommands() = {springy::runRender, springy::runFrames, springy::runReport};
  return springy::runMain(argc, argv);
}

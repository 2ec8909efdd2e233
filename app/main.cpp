// springy: the command line (app/cli.h). render, frames and report run in springy-render.
#include "app/cli.h"

int main(int argc, char** argv) { return springy::runMain(argc, argv); }

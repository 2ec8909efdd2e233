#include "app/gnuplot.h"

#include "app/child.h"
#include "sim/error.h"
#include "sim/interrupt.h"

namespace springy {

bool haveGnuplot() { return !findProgram("gnuplot").empty(); }

void runGnuplot(const std::filesystem::path& script) {
  const std::string gnuplot = findProgram("gnuplot");
  if (gnuplot.empty()) throw Error("gnuplot is not installed (the plots need it): apt install gnuplot-nox");
  if (runChild(gnuplot, {script.filename().string()}, script.parent_path().string()) != 0 && !interrupted()) {
    throw Error("gnuplot failed on " + script.string());
  }
}

std::string gnuplotText(const std::string& text) {
  std::string out = "'";
  // A line break would end the string and start a command (gnuplot's `system` runs a shell):
  // a body or scene named "x\nsystem('...')" is written with spaces instead.
  for (char c : text) out += c == '\'' ? std::string("''") : c == '\n' || c == '\r' ? std::string(" ") : std::string(1, c);
  return out + "'";
}

}  // namespace springy

// springy app: plots drawn by gnuplot (the report's, the studies'). gnuplot runs without a shell,
// in the script's folder, so that no name in a path (a quote, a `;`) is ever read as a command.
#pragma once

#include <filesystem>
#include <string>

namespace springy {

// Whether gnuplot is on PATH.
bool haveGnuplot();

// Runs gnuplot on `script` in the script's folder (its file names are relative to it). Throws
// springy::Error when gnuplot is missing or fails.
void runGnuplot(const std::filesystem::path& script);

// `text` as a gnuplot string literal: in single quotes, a quote doubled, a line break a space.
std::string gnuplotText(const std::string& text);

}  // namespace springy

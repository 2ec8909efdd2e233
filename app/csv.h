// A CSV field (RFC 4180): as it is, or quoted when it holds a comma, a quote or a line break
// (a quote doubled inside). Scene and body names are the user's text.
#pragma once

#include <string>

namespace springy {

inline std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace springy

// Writing CSV shared by the tools.
#pragma once

#include <string>

namespace telegrasp::csv {

/// `s` as one CSV field (RFC 4180): unchanged unless it holds a comma, a double quote, CR or LF;
/// then in double quotes, each double quote inside doubled.
[[nodiscard]] inline std::string field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace telegrasp::csv

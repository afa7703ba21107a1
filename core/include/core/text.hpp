#pragma once
// Small text helpers shared by the parsers of model strings and tau lists, and by the callers
// of helper programs (gnuplot, chromium).

#include <string>
#include <string_view>

namespace calstand::core {

/// `s` without leading and trailing spaces and tabs.
inline std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// `s` as one word for /bin/sh: single-quoted, its own single quotes closed and escaped.
inline std::string shell_quote(std::string_view s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace calstand::core

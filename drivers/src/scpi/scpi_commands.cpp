#include "drivers/scpi_commands.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

namespace calstand::drivers::scpi {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

}  // namespace

const CommandSet* find_command_set(std::string_view model) {
  for (const auto& set : kCommandSets) {
    if (set.model == model) return &set;
  }
  return nullptr;
}

std::optional<double> parse_number(std::string_view reply) {
  reply = trim(reply);
  if (!reply.empty() && reply.front() == '+') reply.remove_prefix(1);  // from_chars takes no '+'
  double value = 0.0;
  const auto [end, ec] = std::from_chars(reply.data(), reply.data() + reply.size(), value);
  if (ec != std::errc() || end != reply.data() + reply.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<bool> parse_boolean(std::string_view reply) {
  std::string upper(trim(reply));
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (upper == "1" || upper == "ON") return true;
  if (upper == "0" || upper == "OFF") return false;
  return std::nullopt;
}

std::optional<ErrorEntry> parse_error_entry(std::string_view reply) {
  reply = trim(reply);
  const auto comma = reply.find(',');
  if (comma == std::string_view::npos) return std::nullopt;
  const auto code = parse_number(reply.substr(0, comma));
  if (!code || *code != std::floor(*code)) return std::nullopt;
  std::string_view text = trim(reply.substr(comma + 1));
  if (text.size() >= 2 && text.front() == '"' && text.back() == '"') {
    text = text.substr(1, text.size() - 2);
  }
  return ErrorEntry{static_cast<int>(*code), std::string(text)};
}

}  // namespace calstand::drivers::scpi

#include <algorithm>
#include <cmath>

#include "json_schema_internal.hpp"

namespace calstand::core::schema_detail {

// Messages must never throw, and a json built in code may hold invalid UTF-8.
std::string dump(const json& v) { return v.dump(-1, ' ', false, json::error_handler_t::replace); }

std::string quote(const std::string& s) { return dump(json(s)); }

/// The value as it appears in the file, shortened so one message stays on one readable line.
std::string describe(const json& v) {
  constexpr std::size_t kMax = 60;
  std::string text = dump(v);
  if (text.size() <= kMax) return text;
  std::size_t cut = kMax - 3;
  // Never split a UTF-8 sequence.
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0u) == 0x80u) --cut;
  return text.substr(0, cut) + "...";
}

std::string join_alternatives(const std::vector<std::string>& items, const char* last_sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += (i + 1 == items.size()) ? last_sep : ", ";
    out += items[i];
  }
  return out;
}

bool is_integral(const json& v) {
  if (v.is_number_integer()) return true;  // signed and unsigned
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && std::floor(d) == d;
}

bool type_matches(unsigned mask, const json& v) {
  switch (v.type()) {
    case json::value_t::null:
      return (mask & kNull) != 0;
    case json::value_t::boolean:
      return (mask & kBoolean) != 0;
    case json::value_t::object:
      return (mask & kObject) != 0;
    case json::value_t::array:
      return (mask & kArray) != 0;
    case json::value_t::string:
      return (mask & kString) != 0;
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float:
      return (mask & kNumber) != 0 || ((mask & kInteger) != 0 && is_integral(v));
    default:
      return false;  // binary and discarded values never come from JSON text
  }
}

std::string expected_phrase(unsigned mask) {
  if ((mask & kNumber) != 0) mask &= ~static_cast<unsigned>(kInteger);
  std::vector<std::string> parts;
  for (const auto& t : kTypeNames) {
    if ((mask & t.bit) != 0) parts.emplace_back(t.phrase);
  }
  return join_alternatives(parts, " or ");
}

std::string got_phrase(const json& v, unsigned expected) {
  switch (v.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return "a boolean";
    case json::value_t::object:
      return "an object";
    case json::value_t::array:
      return "an array";
    case json::value_t::string:
      return "a string";
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
    case json::value_t::number_float:
      // "expected an integer, got a number" would puzzle; show the fraction.
      if ((expected & kInteger) != 0 && !is_integral(v)) return describe(v);
      return "a number";
    default:
      return "an unsupported value";
  }
}

bool is_identifier(const std::string& key) {
  if (key.empty()) return false;
  const auto ident_char = [](char c, bool first) {
    return c == '_' || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
           (!first && c >= '0' && c <= '9');
  };
  if (!ident_char(key[0], true)) return false;
  return std::all_of(key.begin() + 1, key.end(), [&](char c) { return ident_char(c, false); });
}

std::string member_path(const std::string& parent, const std::string& key) {
  if (!is_identifier(key)) return parent + "[" + quote(key) + "]";
  return parent.empty() ? key : parent + "." + key;
}

std::string index_path(const std::string& parent, std::size_t index) {
  return parent + "[" + std::to_string(index) + "]";
}

std::size_t utf8_length(const std::string& s) {
  return static_cast<std::size_t>(std::count_if(
      s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0u) != 0x80u; }));
}

std::string too_long_for_pattern(std::size_t length, const char* what) {
  return std::string(what) + " of " + std::to_string(length) +
         " characters is too long to check against the pattern";
}

}  // namespace calstand::core::schema_detail

#pragma once

// What the json_schema_*.cpp files and json_text.cpp share: the wording of messages and the
// compiled form of a schema. Not installed; the public interface is core/json_schema.hpp.

#include <deque>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <string>
#include <string_view>
#include <vector>

#include "core/json_schema.hpp"
#include "core/suggest.hpp"

namespace calstand::core::schema_detail {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Wording shared by schema load errors, violations and parse errors (json_schema_messages.cpp).

enum TypeBit : unsigned {
  kNull = 1u << 0,
  kBoolean = 1u << 1,
  kObject = 1u << 2,
  kArray = 1u << 3,
  kNumber = 1u << 4,
  kString = 1u << 5,
  kInteger = 1u << 6,
};

struct TypeName {
  const char* keyword;
  const char* phrase;
  unsigned bit;
};

// Listed in the order messages name them.
inline constexpr TypeName kTypeNames[] = {
    {"object", "an object", kObject},
    {"array", "an array", kArray},
    {"string", "a string", kString},
    {"number", "a number", kNumber},
    {"integer", "an integer", kInteger},
    {"boolean", "a boolean", kBoolean},
    {"null", "null", kNull},
};

/// The value as JSON text; never throws, even for a json built in code holding invalid UTF-8.
std::string dump(const json& v);
/// `s` as a JSON string literal.
std::string quote(const std::string& s);
/// The value as it appears in the file, shortened so one message stays on one readable line.
std::string describe(const json& v);
/// "a, b or c" with `last_sep` = " or ".
std::string join_alternatives(const std::vector<std::string>& items, const char* last_sep);
/// An integer, or a float with no fraction (JSON Schema counts 1.0 as an integer).
bool is_integral(const json& v);
/// Whether `v` has one of the types in `mask` (TypeBit values).
bool type_matches(unsigned mask, const json& v);
/// "an object or an array" for a mask of TypeBit values.
std::string expected_phrase(unsigned mask);
/// What `v` is, in the words of expected_phrase().
std::string got_phrase(const json& v, unsigned expected);
bool is_identifier(const std::string& key);
/// `parent.key`, or `parent["odd key"]` when the key is not an identifier.
std::string member_path(const std::string& parent, const std::string& key);
/// `parent[index]`.
std::string index_path(const std::string& parent, std::size_t index);
/// Characters (not bytes) of UTF-8 text.
std::size_t utf8_length(const std::string& s);

/// ` (did you mean "x"?)` for the closest candidate within 2 edits, else empty.
template <typename Range>
inline std::string did_you_mean(const std::string& word, const Range& candidates) {
  std::vector<std::string> owned(std::begin(candidates), std::end(candidates));
  const std::vector<std::string_view> views(owned.begin(), owned.end());
  const std::string best = closest_name(word, views);
  return best.empty() ? std::string() : " (did you mean " + quote(best) + "?)";
}

// ---------------------------------------------------------------------------------------------
// Compiled schema (built by json_schema_compile.cpp, walked by json_schema_validate.cpp).

struct Node;

struct PatternRule {
  std::string source;
  std::regex regex;
  const Node* schema = nullptr;  // unused for "pattern"
};

// std::regex_search recurses once per character for patterns such as "^[a-z]+$" and overflows
// the stack on strings of some tens of thousands of characters; nothing a schema describes is
// that long, so longer strings are reported instead of searched.
inline constexpr std::size_t kMaxPatternChecked = 4096;

std::string too_long_for_pattern(std::size_t length, const char* what);

struct Node {
  std::string pointer;      // JSON pointer of this subschema within the schema document
  std::string label;        // title, or $defs name: names a oneOf/anyOf branch in messages
  bool reject_all = false;  // the boolean schema `false`
  unsigned types = 0;       // 0: any type
  std::optional<json> const_value;
  std::optional<json> enum_values;  // a non-empty array
  std::map<std::string, const Node*> properties;
  std::vector<std::string> required;
  std::vector<PatternRule> pattern_properties;
  const Node* additional = nullptr;
  const Node* property_names = nullptr;
  std::vector<const Node*> prefix_items;
  const Node* items = nullptr;
  std::optional<std::size_t> min_items, max_items;
  bool unique_items = false;
  std::optional<json> minimum, maximum, exclusive_minimum, exclusive_maximum, multiple_of;
  std::optional<std::size_t> min_length, max_length;
  std::optional<PatternRule> pattern;
  std::vector<const Node*> all_of, any_of, one_of;
  const Node* not_schema = nullptr;
  const Node* if_schema = nullptr;
  const Node* then_schema = nullptr;
  const Node* else_schema = nullptr;
  std::string ref_target;  // canonical JSON pointer; resolved into `ref` after compilation
  const Node* ref = nullptr;
};

}  // namespace calstand::core::schema_detail

namespace calstand::core {

struct JsonSchema::Impl {
  std::string name;
  std::deque<schema_detail::Node>
      nodes;  // a deque, so nodes keep their addresses while more are added
  const schema_detail::Node* root = nullptr;
};

}  // namespace calstand::core

#include "core/json_schema.hpp"
#include "core/suggest.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

namespace calstand::core {

using nlohmann::json;

namespace {

// ---------------------------------------------------------------------------------------------
// Wording shared by schema load errors, violations and parse errors.

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
constexpr TypeName kTypeNames[] = {
    {"object", "an object", kObject},
    {"array", "an array", kArray},
    {"string", "a string", kString},
    {"number", "a number", kNumber},
    {"integer", "an integer", kInteger},
    {"boolean", "a boolean", kBoolean},
    {"null", "null", kNull},
};

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

/// ` (did you mean "x"?)` for the closest candidate within 2 edits, else empty.
template <typename Range>
std::string did_you_mean(const std::string& word, const Range& candidates) {
  std::vector<std::string> owned(std::begin(candidates), std::end(candidates));
  const std::vector<std::string_view> views(owned.begin(), owned.end());
  const std::string best = closest_name(word, views);
  return best.empty() ? std::string() : " (did you mean " + quote(best) + "?)";
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

// ---------------------------------------------------------------------------------------------
// Compiled schema.

struct Node;

struct PatternRule {
  std::string source;
  std::regex regex;
  const Node* schema = nullptr;  // unused for "pattern"
};

// std::regex_search recurses once per character for patterns such as "^[a-z]+$" and overflows
// the stack on strings of some tens of thousands of characters; nothing a schema describes is
// that long, so longer strings are reported instead of searched.
constexpr std::size_t kMaxPatternChecked = 4096;

std::string too_long_for_pattern(std::size_t length, const char* what) {
  return std::string(what) + " of " + std::to_string(length) +
         " characters is too long to check against the pattern";
}

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

// clang-format off
const std::set<std::string, std::less<>> kKeywords = {
    "type", "enum", "const",
    "properties", "required", "additionalProperties", "patternProperties", "propertyNames",
    "items", "prefixItems", "minItems", "maxItems", "uniqueItems",
    "minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum", "multipleOf",
    "minLength", "maxLength", "pattern",
    "allOf", "anyOf", "oneOf", "not", "if", "then", "else",
    "$ref", "$defs", "definitions"};
// clang-format on

const std::set<std::string, std::less<>> kAnnotations = {
    "title",    "description", "default", "examples", "deprecated",
    "readOnly", "writeOnly",   "$schema", "$id",      "$comment"};

std::string escape_pointer_token(const std::string& token) {
  std::string out;
  for (char c : token) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

class Compiler {
 public:
  Compiler(const json& root, const std::string& name, std::deque<Node>& nodes)
      : root_(root), name_(name), nodes_(nodes) {}

  Node* compile(const json& s, const std::string& ptr) {
    if (auto it = by_pointer_.find(ptr); it != by_pointer_.end()) return it->second;
    Node& n = nodes_.emplace_back();
    n.pointer = ptr;
    by_pointer_[ptr] = &n;
    if (s.is_boolean()) {
      n.reject_all = !s.get<bool>();
      return &n;
    }
    if (!s.is_object()) {
      fail(ptr, "a schema must be an object or a boolean, got " + got_phrase(s, 0));
    }
    for (const auto& [key, value] : s.items()) {
      if (key.rfind("x-", 0) == 0 || kKeywords.count(key) || kAnnotations.count(key)) continue;
      std::vector<std::string> known(kKeywords.begin(), kKeywords.end());
      known.insert(known.end(), kAnnotations.begin(), kAnnotations.end());
      const std::string hint = did_you_mean(key, known);
      fail(ptr, "unknown keyword " + quote(key) +
                    (hint.empty() ? " (not supported by calstand's schema validator; "
                                    "prefix custom annotations with \"x-\")"
                                  : hint));
    }
    compile_keywords(s, ptr, n);
    return &n;
  }

  /// Points every $ref at its target, compiling targets not reached by the tree walk.
  void resolve_refs() {
    // Compiling a target may add references, so the list grows while it is walked.
    for (std::size_t i = 0; i < pending_refs_.size(); ++i) {
      Node* n = pending_refs_[i];
      const std::string target = n->ref_target;
      auto it = by_pointer_.find(target);
      n->ref = it != by_pointer_.end() ? it->second
                                       : compile(root_.at(json::json_pointer(target)), target);
    }
  }

 private:
  [[noreturn]] void fail(const std::string& ptr, const std::string& why) const {
    throw InputError(name_ + " #" + ptr, why);
  }

  static std::string child(const std::string& ptr, const std::string& token) {
    return ptr + "/" + escape_pointer_token(token);
  }

  std::size_t count(const json& v, const std::string& ptr) const {
    if (!is_integral(v) || v.get<double>() < 0.0) {
      fail(ptr, "must be a non-negative integer, got " + describe(v));
    }
    return v.get<std::size_t>();
  }

  json number(const json& v, const std::string& ptr) const {
    if (!v.is_number()) fail(ptr, "must be a number, got " + describe(v));
    return v;
  }

  PatternRule regex(const std::string& source, const std::string& ptr) const {
    try {
      return PatternRule{source, std::regex(source, std::regex::ECMAScript), nullptr};
    } catch (const std::regex_error& e) {
      fail(ptr, "invalid regular expression " + quote(source) + ": " + e.what());
    }
  }

  std::vector<const Node*> schema_list(const json& v, const std::string& ptr) {
    if (!v.is_array() || v.empty()) fail(ptr, "must be a non-empty array of schemas");
    std::vector<const Node*> out;
    for (std::size_t i = 0; i < v.size(); ++i)
      out.push_back(compile(v[i], child(ptr, std::to_string(i))));
    return out;
  }

  void compile_keywords(const json& s, const std::string& ptr, Node& n) {
    if (auto it = s.find("title"); it != s.end()) {
      if (!it->is_string()) fail(child(ptr, "title"), "must be a string");
      n.label = it->get<std::string>();
    }
    if (auto it = s.find("type"); it != s.end()) n.types = type_mask(*it, child(ptr, "type"));
    if (auto it = s.find("const"); it != s.end()) n.const_value = *it;
    if (auto it = s.find("enum"); it != s.end()) {
      if (!it->is_array() || it->empty()) fail(child(ptr, "enum"), "must be a non-empty array");
      n.enum_values = *it;
    }
    compile_object_keywords(s, ptr, n);
    compile_array_keywords(s, ptr, n);
    for (const auto& [key, slot] :
         {std::pair{"minimum", &n.minimum}, std::pair{"maximum", &n.maximum},
          std::pair{"exclusiveMinimum", &n.exclusive_minimum},
          std::pair{"exclusiveMaximum", &n.exclusive_maximum}}) {
      if (auto it = s.find(key); it != s.end()) *slot = number(*it, child(ptr, key));
    }
    if (auto it = s.find("multipleOf"); it != s.end()) {
      n.multiple_of = number(*it, child(ptr, "multipleOf"));
      if (n.multiple_of->get<double>() <= 0.0) {
        fail(child(ptr, "multipleOf"), "must be greater than 0");
      }
    }
    if (auto it = s.find("minLength"); it != s.end())
      n.min_length = count(*it, child(ptr, "minLength"));
    if (auto it = s.find("maxLength"); it != s.end())
      n.max_length = count(*it, child(ptr, "maxLength"));
    if (auto it = s.find("pattern"); it != s.end()) {
      if (!it->is_string()) fail(child(ptr, "pattern"), "must be a string");
      n.pattern = regex(it->get<std::string>(), child(ptr, "pattern"));
    }
    if (auto it = s.find("allOf"); it != s.end()) n.all_of = schema_list(*it, child(ptr, "allOf"));
    if (auto it = s.find("anyOf"); it != s.end()) n.any_of = schema_list(*it, child(ptr, "anyOf"));
    if (auto it = s.find("oneOf"); it != s.end()) n.one_of = schema_list(*it, child(ptr, "oneOf"));
    for (const auto& [key, slot] :
         {std::pair{"not", &n.not_schema}, std::pair{"if", &n.if_schema},
          std::pair{"then", &n.then_schema}, std::pair{"else", &n.else_schema}}) {
      if (auto it = s.find(key); it != s.end()) *slot = compile(*it, child(ptr, key));
    }
    for (const char* key : {"$defs", "definitions"}) {
      auto it = s.find(key);
      if (it == s.end()) continue;
      if (!it->is_object()) fail(child(ptr, key), "must be an object of schemas");
      for (const auto& [name, sub] : it->items()) {
        Node* def = compile(sub, child(child(ptr, key), name));
        if (def->label.empty()) def->label = name;
      }
    }
    if (auto it = s.find("$ref"); it != s.end()) compile_ref(*it, child(ptr, "$ref"), n);
  }

  unsigned type_mask(const json& v, const std::string& ptr) const {
    const auto one = [&](const json& t) -> unsigned {
      if (t.is_string()) {
        for (const auto& tn : kTypeNames) {
          if (t.get<std::string>() == tn.keyword) return tn.bit;
        }
      }
      std::vector<std::string> names;
      for (const auto& tn : kTypeNames) names.push_back(quote(tn.keyword));
      fail(ptr, describe(t) + " is not a type; use one of " + join_alternatives(names, ", "));
    };
    if (!v.is_array()) return one(v);
    if (v.empty()) fail(ptr, "must name at least one type");
    unsigned mask = 0;
    for (const auto& t : v) mask |= one(t);
    return mask;
  }

  void compile_object_keywords(const json& s, const std::string& ptr, Node& n) {
    if (auto it = s.find("properties"); it != s.end()) {
      if (!it->is_object()) fail(child(ptr, "properties"), "must be an object of schemas");
      for (const auto& [key, sub] : it->items()) {
        n.properties[key] = compile(sub, child(child(ptr, "properties"), key));
      }
    }
    if (auto it = s.find("patternProperties"); it != s.end()) {
      const std::string pp = child(ptr, "patternProperties");
      if (!it->is_object()) fail(pp, "must be an object of schemas");
      for (const auto& [source, sub] : it->items()) {
        PatternRule rule = regex(source, pp);
        rule.schema = compile(sub, child(pp, source));
        n.pattern_properties.push_back(std::move(rule));
      }
    }
    if (auto it = s.find("additionalProperties"); it != s.end()) {
      n.additional = compile(*it, child(ptr, "additionalProperties"));
    }
    if (auto it = s.find("propertyNames"); it != s.end()) {
      n.property_names = compile(*it, child(ptr, "propertyNames"));
    }
    if (auto it = s.find("required"); it != s.end()) {
      const std::string rp = child(ptr, "required");
      if (!it->is_array()) fail(rp, "must be an array of property names");
      for (const auto& r : *it) {
        if (!r.is_string()) fail(rp, "must be an array of property names, has " + describe(r));
        const std::string name = r.get<std::string>();
        // Catches a typo in `required` that would make every document invalid.
        if (n.additional != nullptr && n.additional->reject_all && !n.properties.count(name) &&
            std::none_of(n.pattern_properties.begin(), n.pattern_properties.end(),
                         [&](const PatternRule& p) { return std::regex_search(name, p.regex); })) {
          fail(rp, "required property " + quote(name) +
                       " is not allowed by \"properties\" and \"additionalProperties\": false" +
                       did_you_mean(name, keys_of(n.properties)));
        }
        n.required.push_back(name);
      }
    }
  }

  static std::vector<std::string> keys_of(const std::map<std::string, const Node*>& m) {
    std::vector<std::string> keys;
    for (const auto& [k, v] : m) keys.push_back(k);
    return keys;
  }

  void compile_array_keywords(const json& s, const std::string& ptr, Node& n) {
    if (auto it = s.find("items"); it != s.end()) {
      if (it->is_array()) {
        fail(child(ptr, "items"),
             "must be a single schema; per-position schemas go in \"prefixItems\" (draft 2020-12)");
      }
      n.items = compile(*it, child(ptr, "items"));
    }
    if (auto it = s.find("prefixItems"); it != s.end()) {
      n.prefix_items = schema_list(*it, child(ptr, "prefixItems"));
    }
    if (auto it = s.find("minItems"); it != s.end())
      n.min_items = count(*it, child(ptr, "minItems"));
    if (auto it = s.find("maxItems"); it != s.end())
      n.max_items = count(*it, child(ptr, "maxItems"));
    if (auto it = s.find("uniqueItems"); it != s.end()) {
      if (!it->is_boolean()) fail(child(ptr, "uniqueItems"), "must be true or false");
      n.unique_items = it->get<bool>();
    }
  }

  void compile_ref(const json& v, const std::string& ptr, Node& n) {
    if (!v.is_string()) fail(ptr, "must be a string");
    const std::string ref = v.get<std::string>();
    if (ref.empty() || ref[0] != '#') {
      fail(ptr, "only references within the same schema (starting with \"#\") are supported, got " +
                    quote(ref));
    }
    std::optional<json::json_pointer> target;
    try {
      target.emplace(ref.substr(1));
    } catch (const json::exception&) {
      fail(ptr, quote(ref) + " is not a valid JSON pointer");
    }
    if (!root_.contains(*target)) fail(ptr, "reference target " + quote(ref) + " does not exist");
    n.ref_target = target->to_string();
    pending_refs_.push_back(&n);
  }

  const json& root_;
  const std::string& name_;
  std::deque<Node>& nodes_;
  std::map<std::string, Node*> by_pointer_;
  std::vector<Node*> pending_refs_;
};

// ---------------------------------------------------------------------------------------------
// Validation.

enum class Kind {
  kOther,
  kType,   // wrong JSON type at `path`; `expected` holds the wanted types
  kConst,  // not the one allowed value; `allowed` and `actual` say which
};

struct Finding {
  Finding(std::string p, std::string m, Kind k = Kind::kOther, unsigned e = 0)
      : path(std::move(p)), message(std::move(m)), kind(k), expected(e) {}
  std::string path;
  std::string message;
  Kind kind;
  unsigned expected;
  json allowed;
  std::string actual;
};

using Findings = std::vector<Finding>;

// Generous for any real file, small enough for the stack; also stops a $ref loop in a schema.
constexpr int kMaxDepth = 400;

std::string form_name(const Node& branch, std::size_t index) {
  const Node* b = &branch;
  // A branch that is only a $ref is best named by its target; bounded in case refs loop.
  for (int hops = 0; b->label.empty() && b->ref != nullptr && hops < 8; ++hops) b = b->ref;
  std::string name = "form " + std::to_string(index + 1);
  if (!b->label.empty()) name += " (" + quote(b->label) + ")";
  return name;
}

class Validator {
 public:
  void check(const Node& n, const json& v, const std::string& path, Findings& out,
             int depth) const {
    if (depth > kMaxDepth) {
      out.push_back({path, "nested too deeply to validate (a $ref loop in the schema?)"});
      return;
    }
    if (n.reject_all) {
      out.push_back({path, "no value is allowed here"});
      return;
    }
    if (n.types != 0 && !type_matches(n.types, v)) {
      // Other rules of this schema would only repeat the same mistake.
      out.push_back({path,
                     "expected " + expected_phrase(n.types) + ", got " + got_phrase(v, n.types),
                     Kind::kType, n.types});
      return;
    }
    if (n.const_value && v != *n.const_value) {
      out.push_back(const_finding(path, v, *n.const_value));
    }
    if (n.enum_values) check_enum(*n.enum_values, v, path, out);
    if (v.is_object()) check_object(n, v, path, out, depth);
    if (v.is_array()) check_array(n, v, path, out, depth);
    if (v.is_number()) check_number(n, v, path, out);
    if (v.is_string()) check_string(n, v.get_ref<const std::string&>(), path, out);
    if (n.ref != nullptr) check(*n.ref, v, path, out, depth + 1);
    for (const Node* sub : n.all_of) check(*sub, v, path, out, depth + 1);
    if (!n.any_of.empty()) check_any_of(n.any_of, v, path, out, depth);
    if (!n.one_of.empty()) check_one_of(n.one_of, v, path, out, depth);
    if (n.not_schema != nullptr) {
      Findings inner;
      check(*n.not_schema, v, path, inner, depth + 1);
      if (inner.empty()) {
        out.push_back(
            {path, "matches a form that is not allowed" +
                       (n.not_schema->label.empty() ? std::string()
                                                    : " (" + quote(n.not_schema->label) + ")")});
      }
    }
    if (n.if_schema != nullptr && (n.then_schema != nullptr || n.else_schema != nullptr)) {
      Findings condition;
      check(*n.if_schema, v, path, condition, depth + 1);
      const Node* branch = condition.empty() ? n.then_schema : n.else_schema;
      if (branch != nullptr) check(*branch, v, path, out, depth + 1);
    }
  }

 private:
  static Finding const_finding(const std::string& path, const json& v, const json& allowed) {
    Finding f{path, describe(v) + " is not the required value " + describe(allowed), Kind::kConst};
    f.allowed = allowed;
    f.actual = describe(v);
    return f;
  }

  static void check_enum(const json& values, const json& v, const std::string& path,
                         Findings& out) {
    if (std::find(values.begin(), values.end(), v) != values.end()) return;
    if (values.size() == 1) {
      out.push_back(const_finding(path, v, values[0]));
      return;
    }
    std::vector<std::string> names;
    for (const auto& e : values) names.push_back(describe(e));
    out.push_back({path, describe(v) + " is not one of " + join_alternatives(names, ", ")});
  }

  void check_object(const Node& n, const json& v, const std::string& path, Findings& out,
                    int depth) const {
    for (const auto& r : n.required) {
      if (!v.contains(r)) out.push_back({path, "missing required property " + quote(r)});
    }
    for (const auto& [key, value] : v.items()) {
      const std::string child = member_path(path, key);
      bool known = false;
      if (auto it = n.properties.find(key); it != n.properties.end()) {
        known = true;
        check(*it->second, value, child, out, depth + 1);
      }
      if (!n.pattern_properties.empty() && utf8_length(key) > kMaxPatternChecked) {
        // One finding for the key: not also "unknown property" or a propertyNames message.
        out.push_back({child, too_long_for_pattern(utf8_length(key), "property name")});
        continue;
      }
      for (const auto& rule : n.pattern_properties) {
        if (std::regex_search(key, rule.regex)) {
          known = true;
          check(*rule.schema, value, child, out, depth + 1);
        }
      }
      if (!known && n.additional != nullptr) {
        if (n.additional->reject_all) {
          std::vector<std::string> names;
          for (const auto& [name, sub] : n.properties) names.push_back(name);
          out.push_back({path, "unknown property " + quote(key) + did_you_mean(key, names)});
        } else {
          check(*n.additional, value, child, out, depth + 1);
        }
      }
      if (n.property_names != nullptr) {
        Findings name_findings;
        check(*n.property_names, json(key), std::string(), name_findings, depth + 1);
        for (auto& f : name_findings) {
          out.push_back({child, "invalid property name: " + f.message});
        }
      }
    }
  }

  void check_array(const Node& n, const json& v, const std::string& path, Findings& out,
                   int depth) const {
    const auto items = [](std::size_t k) {
      return std::to_string(k) + (k == 1 ? " item" : " items");
    };
    if (n.min_items && v.size() < *n.min_items) {
      out.push_back({path, "has " + items(v.size()) + ", fewer than the minimum of " +
                               std::to_string(*n.min_items)});
    }
    if (n.max_items && v.size() > *n.max_items) {
      out.push_back({path, "has " + items(v.size()) + ", more than the maximum of " +
                               std::to_string(*n.max_items)});
    }
    for (std::size_t i = 0; i < v.size(); ++i) {
      const Node* sub = i < n.prefix_items.size() ? n.prefix_items[i] : n.items;
      if (sub != nullptr) check(*sub, v[i], index_path(path, i), out, depth + 1);
    }
    if (n.unique_items) {
      // json's ordering compares numbers by value, so 1 and 1.0 collide as the standard wants.
      std::map<json, std::size_t> first_seen;
      for (std::size_t i = 0; i < v.size(); ++i) {
        auto [it, inserted] = first_seen.emplace(v[i], i);
        if (!inserted) {
          out.push_back({path, "items [" + std::to_string(it->second) + "] and [" +
                                   std::to_string(i) + "] are equal; items must be unique"});
        }
      }
    }
  }

  static void check_number(const Node& n, const json& v, const std::string& path, Findings& out) {
    // long double holds every 64-bit integer exactly, so large integer limits compare right.
    const auto x = v.get<long double>();
    const auto limit = [](const std::optional<json>& j) { return j->get<long double>(); };
    const std::string shown = describe(v);
    if (n.minimum && x < limit(n.minimum)) {
      out.push_back({path, shown + " is less than the minimum " + describe(*n.minimum)});
    }
    if (n.maximum && x > limit(n.maximum)) {
      out.push_back({path, shown + " is greater than the maximum " + describe(*n.maximum)});
    }
    if (n.exclusive_minimum && x <= limit(n.exclusive_minimum)) {
      out.push_back({path, shown + " is not greater than the exclusive minimum " +
                               describe(*n.exclusive_minimum)});
    }
    if (n.exclusive_maximum && x >= limit(n.exclusive_maximum)) {
      out.push_back({path, shown + " is not less than the exclusive maximum " +
                               describe(*n.exclusive_maximum)});
    }
    if (n.multiple_of) {
      bool ok = false;
      if (v.is_number_integer() && n.multiple_of->is_number_integer() && !v.is_number_unsigned() &&
          !n.multiple_of->is_number_unsigned()) {
        ok = v.get<std::int64_t>() % n.multiple_of->get<std::int64_t>() == 0;
      } else {
        // Decimal steps such as 0.1 are not exact in binary; allow rounding noise.
        const long double q = x / limit(n.multiple_of);
        ok = std::fabs(q - std::round(q)) <= 1e-9L * std::max(1.0L, std::fabs(q));
      }
      if (!ok) out.push_back({path, shown + " is not a multiple of " + describe(*n.multiple_of)});
    }
  }

  static void check_string(const Node& n, const std::string& s, const std::string& path,
                           Findings& out) {
    const std::string shown = describe(json(s));
    const std::size_t length = utf8_length(s);
    const auto chars = [](std::size_t k) {
      return std::to_string(k) + (k == 1 ? " character" : " characters");
    };
    if (n.min_length && length < *n.min_length) {
      out.push_back(
          {path, shown + " is shorter than the minimum length of " + chars(*n.min_length)});
    }
    if (n.max_length && length > *n.max_length) {
      out.push_back(
          {path, shown + " is longer than the maximum length of " + chars(*n.max_length)});
    }
    if (n.pattern && length > kMaxPatternChecked) {
      out.push_back({path, too_long_for_pattern(length, "string")});
    } else if (n.pattern && !std::regex_search(s, n.pattern->regex)) {
      out.push_back({path, shown + " does not match the pattern \"" + n.pattern->source + "\""});
    }
  }

  void check_any_of(const std::vector<const Node*>& branches, const json& v,
                    const std::string& path, Findings& out, int depth) const {
    std::vector<Findings> results(branches.size());
    for (std::size_t i = 0; i < branches.size(); ++i) {
      check(*branches[i], v, path, results[i], depth + 1);
      if (results[i].empty()) return;
    }
    report_no_match(branches, results, v, path, out);
  }

  void check_one_of(const std::vector<const Node*>& branches, const json& v,
                    const std::string& path, Findings& out, int depth) const {
    std::vector<Findings> results(branches.size());
    std::vector<std::string> matched;
    for (std::size_t i = 0; i < branches.size(); ++i) {
      check(*branches[i], v, path, results[i], depth + 1);
      if (results[i].empty()) matched.push_back(form_name(*branches[i], i));
    }
    if (matched.size() == 1) return;
    if (matched.empty()) {
      report_no_match(branches, results, v, path, out);
      return;
    }
    out.push_back({path, "matches " + std::to_string(matched.size()) + " of the " +
                             std::to_string(branches.size()) + " allowed forms (" +
                             join_alternatives(matched, " and ") + "); exactly one must match"});
  }

  /// One summary for a failed anyOf/oneOf, plus the problems of the form the value most likely
  /// meant: the forms whose type it has and whose fixed values (const, the usual discriminator
  /// of a union) it carries are candidates, and of those the one with fewest problems wins.
  static void report_no_match(const std::vector<const Node*>& branches,
                              const std::vector<Findings>& results, const json& v,
                              const std::string& path, Findings& out) {
    const std::size_t n = branches.size();
    const auto type_miss = [&](const Findings& fs) -> const Finding* {
      for (const auto& f : fs) {
        if (f.kind == Kind::kType && f.path == path) return &f;
      }
      return nullptr;
    };
    const auto const_miss = [](const Findings& fs) -> const Finding* {
      for (const auto& f : fs) {
        if (f.kind == Kind::kConst) return &f;
      }
      return nullptr;
    };

    // Wrong type for every form: name the types that would do.
    unsigned mask = 0;
    bool all_type = true;
    for (const auto& r : results) {
      const Finding* f = type_miss(r);
      all_type = all_type && f != nullptr;
      if (f != nullptr) mask |= f->expected;
    }
    if (all_type) {
      out.push_back({path, "expected " + expected_phrase(mask) + ", got " + got_phrase(v, mask),
                     Kind::kType, mask});
      return;
    }

    const std::string summary = "matches none of the " + std::to_string(n) + " allowed forms";
    std::vector<std::size_t> candidates;
    for (std::size_t i = 0; i < n; ++i) {
      if (type_miss(results[i]) == nullptr && const_miss(results[i]) == nullptr) {
        candidates.push_back(i);
      }
    }

    if (candidates.empty()) {
      // Every form is ruled out by a fixed value; if they all pin the same place, that place
      // holds the union's discriminator, so list its allowed values.
      std::vector<const Finding*> misses;
      for (const auto& r : results) {
        if (const Finding* f = const_miss(r)) misses.push_back(f);
      }
      const bool same_place =
          misses.size() == n && std::all_of(misses.begin(), misses.end(), [&](const Finding* f) {
            return f->path == misses.front()->path;
          });
      if (!same_place) {
        out.push_back({path, summary});
        return;
      }
      std::vector<std::string> allowed;
      for (const Finding* f : misses) {
        const std::string a = describe(f->allowed);
        if (std::find(allowed.begin(), allowed.end(), a) == allowed.end()) allowed.push_back(a);
      }
      Finding disc{misses.front()->path,
                   misses.front()->actual + " is not one of " + join_alternatives(allowed, ", ")};
      if (disc.path != path) out.push_back({path, summary});
      out.push_back(std::move(disc));
      return;
    }

    const auto fewest = std::min_element(
        candidates.begin(), candidates.end(),
        [&](std::size_t a, std::size_t b) { return results[a].size() < results[b].size(); });
    const std::size_t best = *fewest;
    const bool unique = std::count_if(candidates.begin(), candidates.end(), [&](std::size_t i) {
                          return results[i].size() == results[best].size();
                        }) == 1;
    if (!unique) {
      out.push_back({path, summary});
      return;
    }
    out.push_back({path, summary + "; closest is " + form_name(*branches[best], best) +
                             ", whose problems follow"});
    out.insert(out.end(), results[best].begin(), results[best].end());
  }
};

// ---------------------------------------------------------------------------------------------
// Parsing.

/// 1-based line and character column of the 1-based byte position nlohmann reports.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t byte) {
  const std::size_t pos = std::min(byte == 0 ? 0 : byte - 1, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < pos; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else if ((static_cast<unsigned char>(text[i]) & 0xC0u) != 0x80u) {
      ++column;
    }
  }
  return {line, column};
}

/// nlohmann's reason without its exception id and its own (byte-based) location.
std::string parse_reason(const json::parse_error& e) {
  const std::string what = e.what();
  const std::size_t at = what.find("column ");
  const std::size_t colon = at == std::string::npos ? at : what.find(": ", at);
  if (colon != std::string::npos) return what.substr(colon + 2);
  const std::size_t bracket = what.find("] ");
  return bracket == std::string::npos ? what : what.substr(bracket + 2);
}

/// Finds the first key repeated within one object, with the JSON path of that object.
class DuplicateKeyFinder : public nlohmann::json_sax<json> {
 public:
  bool null() override { return element(); }
  bool boolean(bool) override { return element(); }
  bool number_integer(number_integer_t) override { return element(); }
  bool number_unsigned(number_unsigned_t) override { return element(); }
  bool number_float(number_float_t, const string_t&) override { return element(); }
  bool string(string_t&) override { return element(); }
  bool binary(binary_t&) override { return element(); }
  bool start_object(std::size_t) override {
    element();
    frames_.emplace_back(true);
    return true;
  }
  bool key(string_t& k) override {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      duplicate_ = k;
      duplicate_path_ = path_to(frames_.size() - 1);
      return false;  // stops the parse
    }
    f.key = k;
    return true;
  }
  bool end_object() override {
    frames_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override {
    element();
    frames_.emplace_back(false);
    return true;
  }
  bool end_array() override {
    frames_.pop_back();
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const json::exception&) override {
    return false;  // the DOM parse already reported syntax errors
  }

  const std::optional<std::string>& duplicate() const { return duplicate_; }
  const std::string& duplicate_path() const { return duplicate_path_; }

 private:
  struct Frame {
    explicit Frame(bool object) : is_object(object) {}
    bool is_object;
    std::string key;        // current member, objects
    std::size_t index = 0;  // current element, arrays
    std::size_t count = 0;  // elements seen, arrays
    std::set<std::string> keys;
  };

  bool element() {
    if (!frames_.empty() && !frames_.back().is_object)
      frames_.back().index = frames_.back().count++;
    return true;
  }

  std::string path_to(std::size_t depth) const {
    std::string path;
    for (std::size_t i = 0; i < depth; ++i) {
      path = frames_[i].is_object ? member_path(path, frames_[i].key)
                                  : index_path(path, frames_[i].index);
    }
    return path;
  }

  std::vector<Frame> frames_;
  std::optional<std::string> duplicate_;
  std::string duplicate_path_;
};

}  // namespace

// ---------------------------------------------------------------------------------------------

struct JsonSchema::Impl {
  std::string name;
  std::deque<Node> nodes;  // a deque, so nodes keep their addresses while more are added
  const Node* root = nullptr;
};

JsonSchema::JsonSchema(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

JsonSchema JsonSchema::parse(const json& schema, std::string name) {
  auto impl = std::make_shared<Impl>();
  impl->name = std::move(name);
  Compiler compiler(schema, impl->name, impl->nodes);
  impl->root = compiler.compile(schema, "");
  compiler.resolve_refs();
  return JsonSchema(std::move(impl));
}

std::vector<SchemaViolation> JsonSchema::validate(const json& doc) const {
  Findings findings;
  Validator().check(*impl_->root, doc, std::string(), findings, 0);
  std::vector<SchemaViolation> out;
  out.reserve(findings.size());
  for (auto& f : findings) out.push_back({std::move(f.path), std::move(f.message)});
  return out;
}

const std::string& JsonSchema::name() const { return impl_->name; }

namespace {

// InputError writes "where: why"; the file therefore goes in front of every line but the first.
std::string violation_lines(const std::string& file_name,
                            const std::vector<SchemaViolation>& violations) {
  if (violations.empty()) return "does not match its schema";
  std::string text;
  for (std::size_t i = 0; i < violations.size(); ++i) {
    const auto& v = violations[i];
    if (i > 0) text += "\n" + (file_name.empty() ? std::string() : file_name + ": ");
    text += (v.path.empty() ? std::string() : v.path + ": ") + v.message;
  }
  return text;
}

}  // namespace

SchemaError::SchemaError(const std::string& file_name, std::vector<SchemaViolation> violations)
    : InputError(file_name, violation_lines(file_name, violations)),
      violations_(std::move(violations)) {}

void validate_or_throw(const JsonSchema& schema, const json& doc, const std::string& file_name) {
  auto violations = schema.validate(doc);
  if (!violations.empty()) throw SchemaError(file_name, std::move(violations));
}

json parse_json_text(std::string_view text, const std::string& file_name) {
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::parse_error& e) {
    const auto [line, column] = line_column(text, e.byte);
    throw InputError(file_name + ":" + std::to_string(line) + ":" + std::to_string(column),
                     "invalid JSON: " + parse_reason(e));
  }
  DuplicateKeyFinder finder;
  json::sax_parse(text.begin(), text.end(), &finder);
  if (finder.duplicate()) {
    const std::string& path = finder.duplicate_path();
    throw InputError(file_name, (path.empty() ? std::string() : path + ": ") + "key " +
                                    quote(*finder.duplicate()) +
                                    " appears more than once (only one value can be used)");
  }
  return doc;
}

json read_json_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, "is a directory, not a JSON file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw InputError(path, "cannot open: " + std::generic_category().message(err));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "cannot read the file");
  return parse_json_text(text.str(), path);
}

}  // namespace calstand::core

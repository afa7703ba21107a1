#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "json_schema_internal.hpp"

namespace calstand::core {

using nlohmann::json;

namespace schema_detail {
namespace {

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

/// Whether `text` is one bracketed step, `[2]` or `["key"]`, and nothing after it.
bool is_bracket(const std::string& text) {
  if (text.size() < 3 || text.front() != '[' || text.back() != ']') return false;
  if (text[1] != '"') {
    return std::all_of(text.begin() + 1, text.end() - 1,
                       [](char c) { return c >= '0' && c <= '9'; });
  }
  // A quoted key: the closing quote is the last one before "]" (quotes inside are escaped).
  for (std::size_t i = 2; i + 1 < text.size(); ++i) {
    if (text[i] == '\\') {
      ++i;
    } else if (text[i] == '"') {
      return i + 2 == text.size();
    }
  }
  return false;
}

/// Whether `child` is `parent` or one of its direct members (`parent.key`, `parent[2]`,
/// `parent["odd key"]`), as member_path() and index_path() write them.
bool is_member_or_self(const std::string& parent, const std::string& child) {
  if (child == parent) return true;
  if (child.size() <= parent.size() || child.compare(0, parent.size(), parent) != 0) return false;
  const std::string rest = child.substr(parent.size());
  if (parent.empty() || rest.front() == '.') {
    const std::string key = parent.empty() ? rest : rest.substr(1);
    return is_identifier(key) || (parent.empty() && is_bracket(key));
  }
  return rest.front() == '[' && is_bracket(rest);
}

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
    // A union's discriminator is the value itself or one of its members ("transport": "tcp");
    // a fixed value deeper down (a field's "kind" must be "holding") is a problem of the form,
    // not a sign that the value meant another form.
    const auto const_miss = [&](const Findings& fs) -> const Finding* {
      for (const auto& f : fs) {
        if (f.kind == Kind::kConst && is_member_or_self(path, f.path)) return &f;
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

}  // namespace
}  // namespace schema_detail

std::vector<SchemaViolation> JsonSchema::validate(const json& doc) const {
  schema_detail::Findings findings;
  schema_detail::Validator().check(*impl_->root, doc, std::string(), findings, 0);
  std::vector<SchemaViolation> out;
  out.reserve(findings.size());
  for (auto& f : findings) out.push_back({std::move(f.path), std::move(f.message)});
  return out;
}

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

}  // namespace calstand::core

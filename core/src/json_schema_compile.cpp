#include <algorithm>
#include <set>
#include <utility>

#include "json_schema_internal.hpp"

namespace calstand::core {

using nlohmann::json;

namespace schema_detail {
namespace {

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

}  // namespace
}  // namespace schema_detail

JsonSchema::JsonSchema(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

JsonSchema JsonSchema::parse(const json& schema, std::string name) {
  auto impl = std::make_shared<Impl>();
  impl->name = std::move(name);
  schema_detail::Compiler compiler(schema, impl->name, impl->nodes);
  impl->root = compiler.compile(schema, "");
  compiler.resolve_refs();
  return JsonSchema(std::move(impl));
}

const std::string& JsonSchema::name() const { return impl_->name; }

}  // namespace calstand::core

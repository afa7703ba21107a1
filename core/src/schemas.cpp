#include "core/schemas.hpp"

#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace calstand::core {

const JsonSchema& schema(std::string_view file_name) {
  static std::mutex mutex;
  static std::map<std::string, JsonSchema, std::less<>> cache;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(file_name); it != cache.end()) return it->second;
  const auto text = schema_text(file_name);
  if (!text) throw std::logic_error("no compiled-in schema " + std::string(file_name));
  auto parsed =
      JsonSchema::parse(parse_json_text(*text, std::string(file_name)), std::string(file_name));
  return cache.emplace(std::string(file_name), std::move(parsed)).first->second;
}

const JsonSchema& schema_definition(std::string_view file_name, std::string_view def_name) {
  static std::mutex mutex;
  static std::map<std::string, JsonSchema, std::less<>> cache;
  const std::string key = std::string(file_name) + "#/$defs/" + std::string(def_name);
  std::lock_guard lock(mutex);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  const auto text = schema_text(file_name);
  if (!text) throw std::logic_error("no compiled-in schema " + std::string(file_name));
  const nlohmann::json whole = parse_json_text(*text, std::string(file_name));
  const auto defs = whole.find("$defs");
  if (defs == whole.end() || !defs->contains(def_name)) {
    throw std::logic_error("no definition " + key);
  }
  // The definition's own references point into the same $defs ("#/$defs/..."), so a document
  // holding those $defs and referring to the one wanted is that definition, refs and all.
  const nlohmann::json wrapper = {{"$defs", *defs}, {"$ref", "#/$defs/" + std::string(def_name)}};
  return cache.emplace(key, JsonSchema::parse(wrapper, key)).first->second;
}

void validate_part_or_throw(const JsonSchema& schema, const nlohmann::json& part,
                            const std::string& file_name, const std::string& path) {
  auto violations = schema.validate(part);
  if (violations.empty()) return;
  for (auto& v : violations) {
    if (v.path.empty()) {
      v.path = path;
    } else if (!path.empty()) {
      v.path = path + (v.path.front() == '[' ? "" : ".") + v.path;
    }
  }
  throw SchemaError(file_name, std::move(violations));
}

}  // namespace calstand::core

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
  auto parsed = JsonSchema::parse(parse_json_text(*text, std::string(file_name)),
                                  std::string(file_name));
  return cache.emplace(std::string(file_name), std::move(parsed)).first->second;
}

}  // namespace calstand::core

#include "daemon/api/tokens_file.hpp"

#include <fmt/format.h>

#include <set>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"

namespace calstand::daemon::api {

std::vector<NamedToken> load_tokens_file(const std::string& path) {
  const nlohmann::json doc = core::read_json_file(path);
  core::validate_or_throw(core::schema("tokens.schema.json"), doc, path);
  std::vector<NamedToken> out;
  for (const auto& t : doc.at("tokens")) {
    out.push_back({t.at("name").get<std::string>(),
                   t.at("role").get<std::string>() == "read" ? Role::kRead : Role::kOperator,
                   t.at("token").get<std::string>()});
  }
  check_unique_tokens(out, path);
  return out;
}

void check_unique_tokens(const std::vector<NamedToken>& tokens, const std::string& where) {
  // Uniqueness across array items is a rule the schema cannot state.
  std::set<std::string> names;
  std::set<std::string> secrets;
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    if (!names.insert(tokens[i].name).second) {
      throw core::InputError(
          where, fmt::format("tokens[{}].name: '{}' is given twice", i, tokens[i].name));
    }
    if (!secrets.insert(tokens[i].secret).second) {
      throw core::InputError(
          where, fmt::format("tokens[{}].token: the secret of '{}' is another token's too", i,
                             tokens[i].name));
    }
  }
}

}  // namespace calstand::daemon::api

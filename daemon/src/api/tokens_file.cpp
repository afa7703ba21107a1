#include "daemon/api/tokens_file.hpp"

#include <fmt/format.h>

#include <set>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "wire/tokens_store.hpp"

namespace calstand::daemon::api {

std::vector<NamedToken> load_tokens_file(const std::string& path) {
  std::vector<NamedToken> out;
  for (const wire::TokenEntry& e : wire::read_tokens_file(path)) {
    out.push_back(
        {e.name, e.role == "read" ? Role::kRead : Role::kOperator, e.plain_secret, e.id, e.hash});
  }
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
    if (!tokens[i].hashed() && !secrets.insert(tokens[i].secret).second) {
      throw core::InputError(
          where, fmt::format("tokens[{}].token: the secret of '{}' is another token's too", i,
                             tokens[i].name));
    }
  }
}

}  // namespace calstand::daemon::api

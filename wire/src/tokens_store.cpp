#include "wire/tokens_store.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "core/error.hpp"
#include "core/file_output.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "wire/token_hash.hpp"

namespace calstand::wire {
namespace {

void check_unique(const std::vector<TokenEntry>& entries, const std::string& where) {
  // Uniqueness across array items is a rule the schema cannot state.
  std::set<std::string> names;
  std::set<std::string> ids;
  std::set<std::string> secrets;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const TokenEntry& e = entries[i];
    if (!names.insert(e.name).second) {
      throw core::InputError(where, fmt::format("tokens[{}].name: '{}' is given twice", i, e.name));
    }
    if (e.hashed() && !ids.insert(e.id).second) {
      throw core::InputError(
          where, fmt::format("tokens[{}].id: the id of '{}' is another token's too", i, e.name));
    }
    if (!e.hashed() && !secrets.insert(e.plain_secret).second) {
      throw core::InputError(
          where,
          fmt::format("tokens[{}].token: the secret of '{}' is another token's too", i, e.name));
    }
  }
}

}  // namespace

std::vector<TokenEntry> read_tokens_file(const std::string& path, bool missing_ok) {
  if (missing_ok && !std::filesystem::exists(path)) return {};
  const nlohmann::json doc = core::read_json_file(path);
  core::validate_or_throw(core::schema("tokens.schema.json"), doc, path);
  std::vector<TokenEntry> out;
  for (std::size_t i = 0; i < doc.at("tokens").size(); ++i) {
    const auto& t = doc.at("tokens")[i];
    TokenEntry e;
    e.name = t.at("name").get<std::string>();
    e.role = t.at("role").get<std::string>();
    if (t.contains("token")) {
      e.plain_secret = t.at("token").get<std::string>();
    } else {
      e.id = t.at("id").get<std::string>();
      e.hash = t.at("hash").get<std::string>();
      check_token_hash(e.hash, fmt::format("{}: tokens[{}].hash", path, i));
    }
    out.push_back(std::move(e));
  }
  check_unique(out, path);
  return out;
}

void write_tokens_file(const std::string& path, const std::vector<TokenEntry>& entries) {
  nlohmann::json tokens = nlohmann::json::array();
  for (const TokenEntry& e : entries) {
    nlohmann::json t = {{"name", e.name}, {"role", e.role}};
    if (e.hashed()) {
      t["id"] = e.id;
      t["hash"] = e.hash;
    } else {
      t["token"] = e.plain_secret;
    }
    tokens.push_back(std::move(t));
  }
  const nlohmann::json doc = {{"format", kTokensFormat}, {"tokens", tokens}};
  core::write_file_whole(path, doc.dump(2) + "\n");
  // Hashes are no secret a request can use, but names and plain entries are the operator's
  // business: the file stays its owner's.
  if (::chmod(path.c_str(), 0600) != 0) {
    throw core::InputError(path, "written, but its mode cannot be set to 600");
  }
}

std::string add_hashed_token(const std::string& path, const std::string& name,
                             const std::string& role) {
  static const std::regex kName("^[A-Za-z0-9._-]{1,64}$");
  if (!std::regex_match(name, kName)) {
    throw core::InputError("token name", fmt::format("'{}': 1 to 64 of A-Z a-z 0-9 . _ -", name));
  }
  if (role != "read" && role != "operator") {
    throw core::InputError("--role", fmt::format("'{}': read or operator", role));
  }
  std::vector<TokenEntry> entries = read_tokens_file(path, true);
  for (const TokenEntry& e : entries) {
    if (e.name == name) {
      throw core::InputError(path, fmt::format("a token named '{}' is there already (calstand "
                                               "token remove {} first)",
                                               name, name));
    }
  }
  const NewTokenSecret made = new_token_secret();
  TokenEntry e;
  e.name = name;
  e.role = role;
  e.id = made.id;
  e.hash = hash_token_secret(made.secret);
  entries.push_back(std::move(e));
  check_unique(entries, path);
  write_tokens_file(path, entries);
  return made.secret;
}

void remove_token(const std::string& path, const std::string& name) {
  std::vector<TokenEntry> entries = read_tokens_file(path);
  const auto it = std::find_if(entries.begin(), entries.end(),
                               [&](const TokenEntry& e) { return e.name == name; });
  if (it == entries.end()) {
    throw core::InputError(path, fmt::format("no token named '{}'", name));
  }
  if (entries.size() == 1) {
    throw core::InputError(path, fmt::format("'{}' is its last token: a tokens file names at "
                                             "least one; delete the file and calstandd's "
                                             "--tokens instead",
                                             name));
  }
  entries.erase(it);
  write_tokens_file(path, entries);
}

}  // namespace calstand::wire

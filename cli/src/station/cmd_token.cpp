// calstand token add | list | remove: the named bearer tokens of calstandd's --tokens file,
// kept as salted hashes (wire/tokens_store.hpp). `add` prints the secret once: it is nowhere
// else.
#include <fmt/format.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "wire/tokens_store.hpp"

namespace calstand::cli {
namespace {

/// Where the packaged daemon reads its tokens (calstandd --tokens).
constexpr const char* kDefaultTokensFile = "/etc/calstand/tokens.json";

struct TokenOptions {
  std::string file = kDefaultTokensFile;
  std::string name;
  std::string role = "operator";
  bool json = false;
};

void print_list(const TokenOptions& opt) {
  const auto entries = wire::read_tokens_file(opt.file, true);
  if (opt.json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& e : entries) {
      out.push_back({{"name", e.name},
                     {"role", e.role},
                     {"stored", e.hashed() ? "hashed" : "plain"},
                     {"id", e.hashed() ? nlohmann::json(e.id) : nlohmann::json()}});
    }
    fmt::print("{}\n", out.dump(2));
    return;
  }
  if (entries.empty()) {
    fmt::print("{}: no tokens\n", opt.file);
    return;
  }
  fmt::print("{:<24} {:<9} {:<6} {}\n", "NAME", "ROLE", "STORED", "ID");
  for (const auto& e : entries) {
    fmt::print("{:<24} {:<9} {:<6} {}\n", e.name, e.role, e.hashed() ? "hashed" : "plain",
               e.hashed() ? e.id : "-");
  }
}

}  // namespace

void register_token(CLI::App& app) {
  auto opt = std::make_shared<TokenOptions>();
  auto* cmd = app.add_subcommand(
      "token", "Named bearer tokens of calstandd (--tokens FILE), stored as salted hashes");
  cmd->require_subcommand(1);
  const auto file_option = [opt](CLI::App* sub) {
    sub->add_option("--file", opt->file, "Tokens file (calstandd --tokens)")->capture_default_str();
  };

  auto* add = cmd->add_subcommand(
      "add", "Add a token; prints its secret once (the file keeps only a salted hash)");
  add->add_option("name", opt->name, "Name recorded with every action taken with it")->required();
  add->add_option("--role", opt->role, "read or operator")
      ->check(CLI::IsMember({"read", "operator"}))
      ->capture_default_str();
  file_option(add);
  add->callback([opt] {
    const std::string secret = wire::add_hashed_token(opt->file, opt->name, opt->role);
    fmt::print("{}\n", secret);
    fmt::print(stderr,
               "token '{}' ({}) added to {}; the line above is its secret, shown this once: "
               "clients send it as `Authorization: Bearer SECRET` (calstand --token-file)\n",
               opt->name, opt->role, opt->file);
  });

  auto* list = cmd->add_subcommand("list", "List the tokens (names, roles, how each is stored)");
  file_option(list);
  list->add_flag("--json", opt->json, "Print as JSON");
  list->callback([opt] { print_list(*opt); });

  auto* remove = cmd->add_subcommand("remove", "Remove a token");
  remove->add_option("name", opt->name, "The token's name")->required();
  file_option(remove);
  remove->callback([opt] {
    wire::remove_token(opt->file, opt->name);
    fmt::print("token '{}' removed from {}\n", opt->name, opt->file);
  });
}

}  // namespace calstand::cli

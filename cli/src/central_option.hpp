#pragma once
// The central database options every fleet command takes: the address and a password file.

#include <CLI/CLI.hpp>
#include <memory>
#include <pqxx/connection>
#include <string>

#include "core/error.hpp"
#include "fleet/central_address.hpp"

namespace calstand::cli {

struct CentralOptions {
  std::string url;
  std::string password_file;
};

/// Adds `flag` (e.g. --to, --from) for the URL and --password-file; `required` makes the URL
/// required.
inline void add_central_options(CLI::App* cmd, CentralOptions& options, const std::string& flag,
                                const std::string& what, bool required) {
  auto* url = cmd->add_option(flag, options.url,
                              what +
                                  ": postgresql://USER@HOST[:PORT]/DBNAME[?sslmode=...] (no "
                                  "password: it comes from --password-file, PGPASSFILE, "
                                  "~/.pgpass or PGPASSWORD)");
  if (required) url->required();
  cmd->add_option("--password-file", options.password_file,
                  "Password file in libpq's .pgpass format (mode 600)");
}

/// Refuses a command given neither a station file (--db) nor the central database (--from).
inline void require_one_source(const std::string& db, const CentralOptions& central,
                               const std::string& command) {
  if (db.empty() && central.url.empty()) {
    throw core::InputError(command, "give --db FILE or --from postgresql://...");
  }
}

/// Checks the address (fleet::parse_central_address) and connects.
inline std::unique_ptr<pqxx::connection> open_central(const CentralOptions& options,
                                                      const std::string& flag) {
  return fleet::connect_central(
      fleet::parse_central_address(options.url, options.password_file, flag));
}

}  // namespace calstand::cli

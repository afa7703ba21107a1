#include "fleet/central_schema.hpp"

#include <fmt/format.h>

#include <optional>
#include <pqxx/pqxx>
#include <stdexcept>
#include <string_view>

#include "fleet/central_error.hpp"
#include "store/migration_blocks.hpp"

namespace calstand::fleet {
namespace detail {
std::optional<std::string_view> central_schema_file(std::string_view file_name);
}  // namespace detail

namespace {

/// Key of the advisory lock that serialises migrations (any number: 'CSDB' as in SQLite).
constexpr long long kMigrationLockKey = 0x43534442;

const std::vector<store::Migration>& migrations() {
  static const std::vector<store::Migration> m = [] {
    const auto text = detail::central_schema_file("central_schema.sql");
    if (!text) throw std::logic_error("central_schema.sql is not compiled in");
    return store::parse_migrations(*text);
  }();
  return m;
}

struct AppliedVersion {
  int version = 0;  ///< 0: no calstand schema
  std::string title;
};

AppliedVersion applied_version(pqxx::transaction_base& tx) {
  const pqxx::result exists = tx.exec("SELECT to_regclass('calstand_schema') IS NOT NULL");
  if (!exists[0][0].as<bool>()) return {};
  const pqxx::result r =
      tx.exec("SELECT version, title FROM calstand_schema ORDER BY version DESC LIMIT 1");
  if (r.empty()) return {};
  return {r[0][0].as<int>(), r[0][1].as<std::string>()};
}

}  // namespace

int central_schema_version() { return static_cast<int>(migrations().size()); }

std::string central_migration_title(int version) {
  if (version < 1 || version > central_schema_version()) return "";
  return migrations()[static_cast<std::size_t>(version - 1)].title;
}

std::vector<int> migrate_central(pqxx::connection& connection) {
  std::vector<int> applied;
  try {
    for (;;) {
      pqxx::work tx(connection);
      tx.exec("SELECT pg_advisory_xact_lock(" + std::to_string(kMigrationLockKey) + ")");
      tx.exec(
          "CREATE TABLE IF NOT EXISTS calstand_schema (version integer PRIMARY KEY, title text "
          "NOT NULL, applied_utc timestamptz NOT NULL DEFAULT now())");
      const AppliedVersion at = applied_version(tx);
      if (at.version > central_schema_version()) {
        throw CentralError("migrate",
                           fmt::format("the central database is at schema version {} ('{}'), "
                                       "newer than this calstand's {}; use a newer calstand",
                                       at.version, at.title, central_schema_version()));
      }
      if (at.version == central_schema_version()) {
        tx.commit();
        return applied;
      }
      const store::Migration& m = migrations()[static_cast<std::size_t>(at.version)];
      try {
        tx.exec(m.sql);
      } catch (const std::exception& e) {
        throw CentralError(fmt::format("migration {} ('{}')", m.version, m.title), e.what());
      }
      tx.exec_params("INSERT INTO calstand_schema (version, title) VALUES ($1, $2)", m.version,
                     m.title);
      tx.commit();
      applied.push_back(m.version);
    }
  } catch (...) {
    rethrow_as_central("migrate");
  }
}

void require_central_schema(pqxx::connection& connection, const std::string& display,
                            const std::string& who) {
  AppliedVersion at;
  try {
    pqxx::read_transaction tx(connection);
    at = applied_version(tx);
  } catch (...) {
    rethrow_as_central("read the central schema version");
  }
  const int mine = central_schema_version();
  if (at.version == mine) return;
  const std::string operation = "check the central schema of " + display;
  if (at.version == 0) {
    throw CentralError(operation,
                       fmt::format("no calstand schema there; the database's owner creates it "
                                   "with `calstand fleet migrate --to URL` (version {}, '{}')",
                                   mine, central_migration_title(mine)));
  }
  if (at.version < mine) {
    throw CentralError(
        operation,
        fmt::format("the central database is at schema version {} ('{}'), older than {}'s {} "
                    "('{}'); refused: the database's owner migrates it with `calstand fleet "
                    "migrate --to URL`",
                    at.version, at.title, who, mine, central_migration_title(mine)));
  }
  throw CentralError(
      operation, fmt::format("the central database is at schema version {} ('{}'), newer than "
                             "{}'s {} ('{}'); refused: update calstand on {}",
                             at.version, at.title, who, mine, central_migration_title(mine), who));
}

}  // namespace calstand::fleet

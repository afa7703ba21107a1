#pragma once
// The records a fleet-aware command reads: a station's SQLite file (--db) or the fleet's central
// database (--from), behind one store::RecordSource, so that lot and trend run the same analysis
// on either.

#include <string>
#include <utility>

#include "central_option.hpp"
#include "fleet/central_records.hpp"
#include "open_database.hpp"
#include "store/record_source.hpp"

namespace calstand::cli {

/// Opens the one source given (refusing neither, as require_one_source() does) and returns what
/// `use(store::RecordSource&)` returns.
template <class Use>
auto with_record_source(const std::string& db_path, const CentralOptions& central,
                        const std::string& command, Use&& use) {
  require_one_source(db_path, central, command);
  if (!central.url.empty()) {
    auto connection = open_central(central, "--from");
    fleet::CentralRecords records(*connection);
    return std::forward<Use>(use)(static_cast<store::RecordSource&>(records));
  }
  store::Database db = open_existing_database(db_path);
  store::DatabaseRecords records(db);
  return std::forward<Use>(use)(static_cast<store::RecordSource&>(records));
}

}  // namespace calstand::cli

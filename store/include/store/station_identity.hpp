#pragma once

#include <string>

#include "store/database.hpp"

namespace calstand::store {

/// The station's identity in a fleet: a UUID (text, 36 characters, lower case) made once in
/// each database by migration 6. Throws StoreError when the row is missing (a database whose
/// identity was deleted by hand) or SQLite fails.
std::string station_uuid(Database& db);

}  // namespace calstand::store

#include "store/station_identity.hpp"

#include <SQLiteCpp/Statement.h>

#include "sql_util.hpp"

namespace calstand::store {

std::string station_uuid(Database& db) {
  return detail::guarded("read station identity", [&] {
    SQLite::Statement q(db.sql(), "SELECT uuid FROM station_identity WHERE only_row = 1");
    if (!q.executeStep()) {
      throw StoreError("read station identity",
                       db.path() + " has no station identity (table station_identity is empty)");
    }
    return q.getColumn(0).getString();
  });
}

}  // namespace calstand::store

#pragma once
// The form of a versioned schema file: blocks that each start with a line
// `-- migration N: title`, N = 1, 2, 3, ... without gaps. store/schema.sql (the station's SQLite
// database) and fleet/central_schema.sql (the fleet's PostgreSQL database) are both written so.

#include <string>
#include <string_view>
#include <vector>

namespace calstand::store {

/// One migration block of a schema file.
struct Migration {
  int version = 0;
  std::string title;  ///< the text after `N:` on the marker line
  std::string sql;    ///< every line up to the next marker
};

/// The `-- migration N: title` blocks of `schema_text`, in order. Throws std::logic_error when
/// the numbering does not run 1, 2, 3, ... (a broken build, not a user error).
std::vector<Migration> parse_migrations(std::string_view schema_text);

}  // namespace calstand::store

#pragma once
// Opening a database a command only reads from: a missing file is the user's mistake, not a
// new empty database.

#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "store/database.hpp"

namespace calstand::cli {

inline store::Database open_existing_database(const std::string& path) {
  if (!std::filesystem::exists(path)) {
    throw core::InputError("--db " + path, "no such database file");
  }
  return store::Database(path);
}

}  // namespace calstand::cli

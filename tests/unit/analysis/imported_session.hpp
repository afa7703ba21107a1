#pragma once
// Simulated sessions without a table (sim/hand_session.hpp) written as calstand-import/2
// folders and imported, as a user imports a recording made by another tool.

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "sim/hand_session.hpp"
#include "sim/session_folder.hpp"
#include "store/database.hpp"
#include "store/import_export.hpp"

namespace calstand::testing {

/// The session written as an import folder (raw counts with the nominal conversion when
/// `counts`) and imported into `db`; returns the run id.
inline std::int64_t import_session(const sim::SimSession& session, store::Database& db,
                                   const std::string& name, bool counts = false) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("calstand-table-free-" + std::to_string(::getpid()) + "-" + name);
  sim::SessionFolderOptions options;
  options.counts = counts;
  sim::write_session_folder(session, dir, options);
  const auto result = store::import_run(db, dir);
  std::filesystem::remove_all(dir);
  return result.run;
}

}  // namespace calstand::testing

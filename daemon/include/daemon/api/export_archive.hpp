#pragma once

#include <cstdint>
#include <string>

#include "store/database.hpp"

namespace calstand::daemon::api {

/// Run `run` as a `calstand-import/1` folder packed in a ustar archive (in memory):
/// `run-ID/meta.json` and `run-ID/samples.csv`, exactly as `calstand export` writes them.
/// `device` picks the IMU (empty: the run's only one). Throws as store::export_run().
std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device);

}  // namespace calstand::daemon::api

#pragma once
// One signal of a recorded run, downsampled on the server for a plot (GET /runs/{id}/series).

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/downsample.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// A signal a run's series can show: its name, unit and what it is.
struct SeriesSignal {
  const char* name;
  const char* unit;
  const char* meaning;
};

/// gx gy gz [deg/s], ax ay az [m/s^2], temp_c (IMU samples, read chunk by chunk) and
/// table_outer_deg, table_inner_deg, table_outer_rate_dps, table_inner_rate_dps (the table at
/// each sample, read a completed step at a time).
const std::vector<SeriesSignal>& series_signals();

struct SeriesRequest {
  std::string signal;             ///< one of series_signals()
  std::string device;             ///< "" = the run's only IMU
  std::size_t max_points = 2000;  ///< at most this many buckets, >= 2
  /// Window in seconds since the run's first sample (of its first step with samples).
  double from_s = -std::numeric_limits<double>::infinity();
  double to_s = std::numeric_limits<double>::infinity();
};

struct RunSeries {
  std::string signal;
  std::string unit;
  std::string device;
  DownsampledSeries series;  ///< `samples`: samples in the window
};

/// Reads `request.signal` of `run` step by step (IMU channels chunk by chunk: a long run is
/// never in memory at once) and downsamples it. Throws RunNotFound, NothingToFit (no samples),
/// or core::InputError naming "signal", "max_points", "from_s/to_s" or the run (bad device).
RunSeries run_series(store::Database& db, std::int64_t run, const SeriesRequest& request);

/// {"signal", "unit", "t_s": [...], "min": [...], "max": [...], "mean": [...], "samples"}.
nlohmann::json to_json(const RunSeries& series);

}  // namespace calstand::analysis

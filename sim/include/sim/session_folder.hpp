#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "sim/hand_session.hpp"

/// A simulated session (sim/hand_session.hpp) written as the user of another tool would have
/// it: a `calstand-import/2` folder (../shared/docs/error-model.md) without the table columns,
/// plus the truth it was made from.
namespace calstand::sim {

struct SessionFolderOptions {
  /// Write raw counts with a nominal conversion in meta.json (`nominal`), rounded to whole
  /// counts: gyro 32768 + 80 counts per deg/s, accel 32768 + 2000 counts per m/s^2 (a 16-bit
  /// part of +-409 deg/s and +-16 m/s^2; values outside are not clipped). Off: deg/s and m/s^2.
  bool counts = false;
  bool temperature = true;  ///< a temp_c column (and units.temperature)
};

/// The nominal conversion used for counts: {offset, counts per unit} per sensor.
inline constexpr double kSessionGyroOffsetCounts = 32768.0;
inline constexpr double kSessionGyroCountsPerDps = 80.0;
inline constexpr double kSessionAccelOffsetCounts = 32768.0;
inline constexpr double kSessionAccelCountsPerMps2 = 2000.0;

/// meta.json of the session: format calstand-import/2, site with gravity_mps2, no `table`,
/// sample_rate_hz, units, `nominal` for counts, and for a Ferraris session the `sections`
/// extension: {"<step>": {"label": "x_p", "kind": "static", "up": "+x"} or
/// {"label": "x_rot", "kind": "turn", "axis": "+x", "angle_deg": 360}} (angle right-handed
/// about the axis; the moves between sections have step numbers of their own and no entry).
nlohmann::json session_meta_json(const SimSession& s, const SessionFolderOptions& options);

/// truth.json: {"format": "calstand-sim-session-truth/1", "kind", "model", "seed",
/// "frame" (the convention in words), "C_AB" (simulator body to frame A, rows),
/// "parameters": {name: value} in frame A and contract units, "units": {term: unit},
/// "session": {"slow_noise_mean_over_holds": {"gyro_bias.x": ...}, "initial_rest": {...}},
/// "holds": [{"start_s", "end_s", "up_A", "label"?, "placement_tilt_deg"?}],
/// "turns": [{"start_s", "end_s", "axis_A", "angle_deg", "peak_rate_dps", "label"?}]}.
nlohmann::json session_truth_json(const SimSession& s);

/// Writes meta.json, samples.csv (`t,gx,gy,gz,ax,ay,az[,temp_c][,step]`, step for a Ferraris
/// session) and truth.json into `dir` (created when missing). Throws std::runtime_error naming
/// the file when one cannot be written.
void write_session_folder(const SimSession& s, const std::filesystem::path& dir,
                          const SessionFolderOptions& options);

}  // namespace calstand::sim

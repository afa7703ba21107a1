#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/station_config.hpp"
#include "daemon/run_engine.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "store/run_store.hpp"
#include "store/units.hpp"

namespace calstand::daemon {

/// Serials given with a run for its units, by IMU name (`--unit imu0=SN1234`).
using UnitSerials = std::map<std::string, std::string>;

/// The unit in each IMU slot of `station` for a new run: the serial given with the run
/// ("submitted"), else the one in the station file ("station"), else none. A simulated IMU
/// reports its serial when the run starts, which the engine checks against this. Throws
/// core::InputError naming `units.NAME` for a slot the station lacks or an empty serial, and
/// naming the slot when the station requires serials (`require_serial`) and one has none.
std::vector<store::RunUnit> units_for_run(const core::StationConfig& station,
                                          const UnitSerials& submitted);

/// Records a new run of `plan` (procedure text and hash, parameters, station snapshot, the
/// expanded steps, its units: units_for_run, checked before anything is written) and returns
/// its id. Nothing runs.
std::int64_t create_run_record(store::RunStore& runs, const core::StationConfig& station,
                               const procedures::Procedure& procedure, const procedures::Plan& plan,
                               const UnitSerials& submitted = {});

/// How a campaign ended.
struct CampaignResult {
  RunState state = RunState::kIdle;
  std::string exit_reason;
  double station_time_s = 0.0;  ///< station clock at the end [s]
};

/// Where to start and how: a new run starts at step 0, attempt 1, time 0; a resumed run at its
/// first unfinished step, one attempt past those recorded, at the last recorded station time.
struct CampaignStart {
  std::size_t first_step = 0;
  int first_attempt = 1;
  double start_time_s = 0.0;
  /// Steps before `first_step` the operator skipped: a resumed run re-establishes the state
  /// the completed steps left, not what a skipped one would have.
  std::vector<std::size_t> skipped_steps;
};

/// Runs run `run_id` (already recorded in the database at `db_path`) on the station of
/// `station`, wired by StationRun as calstandd wires its runs: the station's devices, a capture
/// writer and the engine with the station's fault policy. `on_tick` is called from the engine
/// thread on every progress update, with the engine (for operator requests such as pause or
/// abort, which it queues). Blocks until the run ends.
CampaignResult run_campaign(const core::StationConfig& station, const procedures::Plan& plan,
                            const std::string& db_path, std::int64_t run_id,
                            const CampaignStart& start = {},
                            std::function<void(RunEngine&, const Progress&)> on_tick = {});

}  // namespace calstand::daemon

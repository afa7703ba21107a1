#pragma once

#include <cstdint>
#include <string>

#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon {

/// A recorded run made ready to execute: its own procedure text, parameters and station,
/// exactly as they were when it was created, and where to start.
struct StoredRun {
  core::StationConfig station;
  procedures::Plan plan;
  CampaignStart start;
  std::string procedure_name;
};

/// Prepares run `run` (never started, or cut off by a crash, kill or daemon stop) to execute
/// from its first unfinished step: the samples of every attempt of unfinished steps are
/// discarded (a cut-off attempt's data is incomplete), the next attempt number follows those
/// recorded, and the station clock continues from the last recorded time.
///
/// Throws core::InputError naming the run when it has ended (completed, aborted, failed,
/// imported), when every step is already done, or when its stored procedure no longer expands
/// to its stored steps; ProcedureError when the stored plan breaks a rule.
StoredRun prepare_stored_run(store::RunStore& runs, std::int64_t run);

}  // namespace calstand::daemon

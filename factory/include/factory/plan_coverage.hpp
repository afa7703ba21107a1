#pragma once
// What a procedure can determine for each unit of a fixture, before anything moves: `calstand
// plan` asks it. Moves given by pointing are resolved for one IMU's mount; on a fixture the other
// units sit at other mounts, so the same table angles may leave one of their axes unexcited.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/station_config.hpp"
#include "procedures/plan.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"

namespace calstand::analysis {

/// The parameters of the model one unit's data from the plan would leave undetermined.
struct UnitCoverage {
  std::string imu;
  std::size_t recording_steps = 0;
  std::vector<solver::Unidentifiable> undetermined;  ///< empty: the plan determines them all
};

struct PlanCoverage {
  std::string model;                ///< Model::text()
  std::vector<UnitCoverage> units;  ///< in the station's IMU order
};

/// For each IMU of `station`: the step means the plan's recording steps would give (the table
/// at each commanded position, rate steps swept over their angle, temperatures at the
/// setpoints, the unit's mount), fitted noise-free with the solver's own identifiability rules
/// (solver::fit_model): what it reports undetermined is what the procedure cannot determine for
/// that unit. A plan with fewer recorded values than parameters leaves them all undetermined.
PlanCoverage plan_coverage(const procedures::Plan& plan, const core::StationConfig& station,
                           const solver::Model& model);

/// `{"model", "units": [{"imu", "recording_steps", "undetermined": [{"name", "reason"}]}]}`.
nlohmann::json to_json(const PlanCoverage& coverage);

}  // namespace calstand::analysis

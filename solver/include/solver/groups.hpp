#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/fit.hpp"

namespace calstand::solver {

/// The conditions of a step, as words a person groups by.
struct StepConditions {
  std::string plateau;      ///< "T 70 degC"
  std::string orientation;  ///< "+z up", "-x up", or "turning" (no axis holds still vertically)
  std::string rate;         ///< "static", "|w| 30 deg/s"
  std::string direction;    ///< "static", "+ (CCW about +x)", ...: the sign of the turn
  std::string axis;         ///< "static", "about body z"
  std::string time;         ///< "run 1st quarter" ... "run 4th quarter"
};

/// The conditions of each step of a fit (by position in `steps`).
std::vector<StepConditions> step_conditions(const std::vector<StepSummary>& steps);

/// One group of steps sharing a condition, with the fit's chi-square per degree of freedom over
/// its step-mean rows (z-scores of the channels the fit used).
struct GroupQuality {
  std::string group;  ///< e.g. "plateau: T 70 degC"
  double chi2_dof = 0.0;
  std::vector<std::size_t> steps;  ///< step indexes in the run
};

/// Every group of every condition kind, worst (highest chi2/dof) first. Groups that hold every
/// step (nothing to contrast) are left out.
std::vector<GroupQuality> group_quality(const FitResult& fit,
                                        const std::vector<StepSummary>& steps);

/// A step-mean residual far from its noise.
struct WorstStep {
  std::size_t step = 0;
  std::string channel;  ///< gx .. az
  double z = 0.0;
};

/// The `count` largest |z| over steps and the fit's channels, largest first.
std::vector<WorstStep> worst_steps(const FitResult& fit, std::size_t count = 10);

/// `"groups"` and `"worst_steps"` added to a fit's JSON.
void add_groups_json(nlohmann::json& fit_json, const std::vector<GroupQuality>& groups,
                     const std::vector<WorstStep>& worst);

/// The channels a fit used.
std::vector<int> fit_channels(SensorRows rows);

}  // namespace calstand::solver

#include "factory/plan_coverage.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "solver/run_setup.hpp"
#include "solver/signals.hpp"
#include "solver/step_summary.hpp"

namespace calstand::analysis {
namespace {

/// Points a rate step's sweep is averaged over: enough that a whole revolution averages a
/// position-dependent regressor (gravity in the rotating body) to well below the collinearity
/// threshold of the fit.
constexpr int kSweepPoints = 72;

/// Whether a parameter is determined depends on the noise too: the fit calls one "barely
/// excited" when its sigma would exceed what any real sensor has (a gyro scale factor from the
/// Earth rate alone, say). The plan has no data yet, so the step means are weighed with an
/// LN200-class unit's white noise at its output rate (angle random walk 0.07 deg/sqrt(h),
/// velocity random walk 0.03 m/s/sqrt(h), 400 Hz). A noisier unit determines less; the bias
/// wander of a real one does too, so this is the optimistic side.
constexpr double kRateHz = 400.0;
constexpr double kGyroWhiteDpsPerRootHz = 0.07 / 60.0;    ///< [deg/s/sqrt(Hz)] = 0.07 deg/sqrt(h)
constexpr double kAccelWhiteMps2PerRootHz = 0.03 / 60.0;  ///< 0.03 m/s/sqrt(h)

struct TablePose {
  double outer_deg = 0.0;
  double inner_deg = 0.0;
};

/// The unit's temperature as the plan sees it (no chamber or IMU lag, as the plan's durations):
/// a soaked set point is reached at once; a set point without a soak is ramped to from where
/// the last one left it, so that the steps recorded during a ramp are points at their own
/// temperatures (thermal-ramp), not all at its target.
class PlannedTemperature {
 public:
  explicit PlannedTemperature(const core::StationConfig& station)
      : now_c_(station.chamber.ambient_c),
        max_ramp_c_per_min_(station.chamber.max_ramp_c_per_min) {}

  void set(const procedures::Step& step, double start_s) {
    from_c_ = at(start_s);
    target_c_ = step.target_c;
    ramp_start_s_ = start_s;
    ramp_c_per_min_ = step.wait_for_soak ? 0.0 : step.ramp_c_per_min.value_or(max_ramp_c_per_min_);
    now_c_ = target_c_;
  }

  /// [degC] at plan time `time_s`.
  double at(double time_s) const {
    if (!(ramp_c_per_min_ > 0.0)) return now_c_;
    const double ramped_c = ramp_c_per_min_ * (time_s - ramp_start_s_) / 60.0;
    return target_c_ >= from_c_ ? std::min(target_c_, from_c_ + ramped_c)
                                : std::max(target_c_, from_c_ - ramped_c);
  }

 private:
  double now_c_;
  double max_ramp_c_per_min_;
  double from_c_ = 0.0;
  double target_c_ = 0.0;
  double ramp_start_s_ = 0.0;
  double ramp_c_per_min_ = 0.0;  ///< 0: at the set point
};

// The mean regressors and reference of one recording step of a unit.
solver::StepSummary summarize(const procedures::Step& step, const TablePose& pose,
                              double temperature_c, double start_s,
                              const solver::SignalBuilder& build, const solver::Model& model) {
  const bool rotating = step.kind == procedures::StepKind::kRate;
  const int points = rotating ? kSweepPoints : 1;
  const double sweep_deg = rotating ? step.rate_dps * step.duration_s : 0.0;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(solver::kChannels, model.size());
  Eigen::MatrixXd one(solver::kChannels, model.size());
  solver::Vector6d reference = solver::Vector6d::Zero();
  std::array<double, solver::kSignalCount> signals{};
  for (int k = 0; k < points; ++k) {
    store::TableSample table{pose.outer_deg, pose.inner_deg, 0.0, 0.0};
    if (rotating) {
      // Midpoints of the sweep: the mean over the recording, not its two ends.
      const double angle = sweep_deg * (k + 0.5) / points;
      if (step.axis == "outer") {
        table.outer_deg += angle;
        table.outer_rate_dps = step.rate_dps;
      } else {
        table.inner_deg += angle;
        table.inner_rate_dps = step.rate_dps;
      }
    }
    core::ImuSample sample;
    sample.temperature_c = temperature_c;
    const solver::Signals s = build(sample, table, 0.0, start_s);
    model.regressors(s, one);
    sum += one;
    reference += model.reference(s);
    const auto values = solver::signal_values(s);
    for (std::size_t i = 0; i < signals.size(); ++i) signals[i] += values[i] / points;
  }
  solver::StepSummary out;
  out.index = step.index;
  out.label = step.label;
  out.count = std::max<std::int64_t>(1, std::llround(step.duration_s * kRateHz));
  out.duration_s = step.duration_s;
  out.start_s = start_s;
  out.end_s = start_s + step.duration_s;
  out.regressors = sum / points;
  out.reference = reference / points;
  out.measured = out.reference;  // noise-free: only which columns the data excite matters
  out.signals = signals;
  out.is_static = !rotating;
  return out;
}

UnitCoverage unit_coverage(const procedures::Plan& plan, const core::StationConfig& station,
                           std::size_t imu, const solver::Model& model) {
  solver::RunSetup setup;
  setup.device = station.imus[imu].name;
  setup.site = station.site;
  setup.geometry = station.geometry(imu);
  const solver::SignalBuilder build(setup, model.earth_rate());
  TablePose pose;
  PlannedTemperature temperature(station);
  std::vector<solver::StepSummary> steps;
  for (std::size_t i = 0; i < plan.steps.size(); ++i) {
    const procedures::Step& step = plan.steps[i];
    switch (step.kind) {
      case procedures::StepKind::kMove:
        pose = {step.outer_deg, step.inner_deg};
        break;
      case procedures::StepKind::kSetTemperature:
        temperature.set(step, plan.step_start_s.at(i));
        break;
      case procedures::StepKind::kCapture:
      case procedures::StepKind::kRate:
        steps.push_back(summarize(step, pose,
                                  temperature.at(plan.step_start_s.at(i) + 0.5 * step.duration_s),
                                  plan.step_start_s.at(i), build, model));
        break;
      case procedures::StepKind::kWait:
      case procedures::StepKind::kPower:
      // An oscillation's mean rate is nil: at its pose it adds what a capture there would, which
      // the plan gives separately if the model needs it; it is for the bandwidth analysis.
      case procedures::StepKind::kOscillate:
        break;
    }
  }
  UnitCoverage out;
  out.imu = setup.device;
  out.recording_steps = steps.size();
  solver::NoiseFloor floor;
  // Per-sample variance: the white density times the sample rate.
  floor.density.head<3>().setConstant(kGyroWhiteDpsPerRootHz * kGyroWhiteDpsPerRootHz * kRateHz);
  floor.density.tail<3>().setConstant(kAccelWhiteMps2PerRootHz * kAccelWhiteMps2PerRootHz *
                                      kRateHz);
  try {
    out.undetermined = solver::fit_model(steps, model, floor).unidentifiable;
  } catch (const core::InputError&) {
    // Fewer recorded values than parameters: nothing is determined.
    for (const auto& p : model.parameters()) {
      out.undetermined.push_back(
          {p.name, "the procedure records too few steps for this model", {}});
    }
  }
  return out;
}

}  // namespace

PlanCoverage plan_coverage(const procedures::Plan& plan, const core::StationConfig& station,
                           const solver::Model& model) {
  PlanCoverage out;
  out.model = model.text();
  for (std::size_t i = 0; i < station.imus.size(); ++i) {
    out.units.push_back(unit_coverage(plan, station, i, model));
  }
  return out;
}

nlohmann::json to_json(const PlanCoverage& coverage) {
  nlohmann::json units = nlohmann::json::array();
  for (const UnitCoverage& u : coverage.units) {
    nlohmann::json undetermined = nlohmann::json::array();
    for (const auto& p : u.undetermined) {
      undetermined.push_back({{"name", p.name}, {"reason", p.reason}});
    }
    units.push_back(
        {{"imu", u.imu}, {"recording_steps", u.recording_steps}, {"undetermined", undetermined}});
  }
  return {{"model", coverage.model}, {"units", units}};
}

}  // namespace calstand::analysis

// A first look at an IMU from a recorded run: position means, two-position accelerometers, a
// CW/CCW rate test and a chamber step, as the seed notes compute them by hand.
#include "analysis/first_look.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "analysis/run_model.hpp"
#include "core/rotation.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

struct Means {
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
  double temperature_c = 0.0;
  std::size_t samples = 0;
};

Means means_of(const store::StepData& data) {
  Means m;
  for (const auto& s : data.samples) {
    m.gyro_dps += s.gyro_dps;
    m.accel_mps2 += s.accel_mps2;
    m.temperature_c += s.temperature_c;
  }
  m.samples = data.samples.size();
  if (m.samples > 0) {
    const double n = static_cast<double>(m.samples);
    m.gyro_dps /= n;
    m.accel_mps2 /= n;
    m.temperature_c /= n;
  }
  return m;
}

// Mean of angles that may wrap (179.9 and -179.9) [deg].
double circular_mean_deg(const std::vector<store::TableSample>& table,
                         double store::TableSample::*angle) {
  double s = 0.0, c = 0.0;
  for (const auto& t : table) {
    s += std::sin(t.*angle * std::numbers::pi / 180.0);
    c += std::cos(t.*angle * std::numbers::pi / 180.0);
  }
  return std::atan2(s, c) * 180.0 / std::numbers::pi;
}

// The pointing ("+x" ... "-z") of the move step right before `index`, if it was given so.
std::optional<std::pair<int, int>> pointing_before(const std::vector<store::StepRecord>& steps,
                                                   std::size_t index) {
  if (index == 0) return std::nullopt;
  const auto& prev = steps[index - 1];
  if (prev.kind != "move" || !prev.commanded.contains("up")) return std::nullopt;
  const std::string up = prev.commanded["up"].get<std::string>();
  if (up.size() != 2 || up[1] < 'x' || up[1] > 'z') return std::nullopt;
  return std::pair<int, int>{up[1] - 'x', up[0] == '+' ? +1 : -1};
}

// A rate capture seen while reading, with the table state it ran at.
struct RateSeen {
  RateCapture capture;
  std::string table_axis;
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  double start_outer_deg = 0.0;
  double start_inner_deg = 0.0;
};

// The first pair of rate captures about one axis with opposite rates of equal size.
std::optional<std::pair<RateSeen, RateSeen>> cw_ccw_pair(const std::vector<RateSeen>& rates) {
  for (std::size_t i = 0; i < rates.size(); ++i) {
    for (std::size_t j = i + 1; j < rates.size(); ++j) {
      const auto& a = rates[i].capture;
      const auto& b = rates[j].capture;
      if (rates[i].table_axis != rates[j].table_axis) continue;
      if (std::abs(a.rate_dps + b.rate_dps) > 1e-9 * std::abs(a.rate_dps)) continue;
      return a.rate_dps > 0 ? std::pair{rates[i], rates[j]} : std::pair{rates[j], rates[i]};
    }
  }
  return std::nullopt;
}

RateTest rate_test(const solver::RunSetup& setup, const RateSeen& pos, const RateSeen& neg) {
  RateTest t;
  t.table_axis = pos.table_axis;
  const bool inner = t.table_axis == "inner";
  // The still axis sits at its mean; the turning one's start angle is reported.
  t.outer_deg = inner ? pos.outer_deg : pos.start_outer_deg;
  t.inner_deg = inner ? pos.start_inner_deg : pos.inner_deg;
  // The turning axis in L, and in B (fixed in B while that axis turns alone).
  const Eigen::Vector3d axis_level =
      setup.geometry.table_rate_level_dps(pos.outer_deg, inner ? 0.0 : 1.0, inner ? 1.0 : 0.0);
  const Eigen::Vector3d axis_body =
      setup.geometry.body_to_level(pos.outer_deg, pos.inner_deg).transpose() * axis_level;
  axis_body.cwiseAbs().maxCoeff(&t.body_axis);
  t.direction = axis_body[t.body_axis] > 0 ? +1 : -1;
  // Over whole revolutions only the Earth rate's part along the turning axis stays.
  const double earth_along_dps =
      axis_level.dot(setup.site.earth_rate_level_radps()) * core::kRadToDeg;
  auto fill = [&](const RateSeen& seen) {
    RateCapture c = seen.capture;
    c.gyro_dps = seen.gyro_dps[t.body_axis];
    c.reference_dps = axis_body[t.body_axis] * (c.rate_dps + earth_along_dps);
    return c;
  };
  t.positive = fill(pos);
  t.negative = fill(neg);
  t.scale_ppm = ((t.positive.gyro_dps - t.negative.gyro_dps) /
                     (t.positive.reference_dps - t.negative.reference_dps) -
                 1.0) *
                1e6;
  t.bias_dps = 0.5 * ((t.positive.gyro_dps + t.negative.gyro_dps) -
                      (t.positive.reference_dps + t.negative.reference_dps));
  return t;
}

// Chamber telemetry at time_s: the first row at or after it (the last row before, if none).
const core::ChamberState* chamber_at(const std::vector<core::ChamberState>& rows, double time_s) {
  if (rows.empty()) return nullptr;
  const auto it =
      std::lower_bound(rows.begin(), rows.end(), time_s,
                       [](const core::ChamberState& r, double t) { return r.time_s < t; });
  return it == rows.end() ? &rows.back() : &*it;
}

}  // namespace

FirstLook first_look(store::Database& db, std::int64_t run, const std::string& device) {
  FirstLook look;
  look.run = run;
  look.device = choose_fit_device(db, run, device);  // the checks and messages of a fit
  const std::string where = fmt::format("run {}", run);
  store::RunStore runs(db);
  const solver::RunSetup setup = solver::run_setup(runs.load_run(run), run, look.device);
  look.gravity_mps2 = setup.site.gravity();
  look.latitude_deg = setup.site.latitude_deg;
  look.earth_rate_level_dph = setup.site.earth_rate_level_radps() * core::kRadToDeg * 3600.0;

  const std::vector<store::StepRecord> steps = runs.load_steps(run);
  std::optional<std::size_t> last_set_temperature;
  for (const auto& s : steps) {
    if (s.kind == "set_temperature" && s.started_clock_s) last_set_temperature = s.index;
    if (s.ended_clock_s) look.station_time_s = std::max(look.station_time_s, *s.ended_clock_s);
  }

  std::vector<RateSeen> rates;
  std::vector<store::StepData> watch;  // captures after the last set_temperature step
  store::for_each_step_data(db, run, look.device, [&](const store::StepData& data) {
    const std::size_t index = data.step.index;
    const Means m = means_of(data);
    if (data.step.kind == "capture" && last_set_temperature && index > *last_set_temperature) {
      ThermalMark mark;
      mark.step = index;
      mark.imu_c = m.temperature_c;
      const double t0 = *steps[*last_set_temperature].started_clock_s;
      const double start = data.step.started_clock_s.value_or(t0);
      mark.t_min = (start - t0) / 60.0;
      look.thermal.push_back(mark);
      watch.push_back(store::StepData{data.step, {}, {}});
      return;
    }
    if (data.step.kind == "capture") {
      const auto pointing = pointing_before(steps, index);
      if (!pointing) return;
      PositionMean p;
      p.step = index;
      p.label = data.step.label;
      p.axis = pointing->first;
      p.sign = pointing->second;
      p.outer_deg = steps[index - 1].commanded.value("outer_deg", 0.0);
      p.inner_deg = steps[index - 1].commanded.value("inner_deg", 0.0);
      p.gyro_dps = m.gyro_dps;
      p.accel_mps2 = m.accel_mps2;
      p.temperature_c = m.temperature_c;
      p.samples = m.samples;
      look.positions.push_back(p);
      return;
    }
    if (data.step.kind == "rate" && !data.table.empty()) {
      RateSeen r;
      r.capture.step = index;
      r.capture.label = data.step.label;
      r.capture.rate_dps = data.step.commanded.value("rate_dps", 0.0);
      r.capture.samples = m.samples;
      r.table_axis = data.step.commanded.value("axis", "");
      r.gyro_dps = m.gyro_dps;
      r.outer_deg = circular_mean_deg(data.table, &store::TableSample::outer_deg);
      r.inner_deg = circular_mean_deg(data.table, &store::TableSample::inner_deg);
      r.start_outer_deg = data.table.front().outer_deg;
      r.start_inner_deg = data.table.front().inner_deg;
      rates.push_back(r);
    }
  });
  if (look.positions.empty() && rates.empty() && look.thermal.empty()) {
    throw NothingToFit(where,
                       "has no capture after a move by pointing (\"up\"), no rate step "
                       "and no chamber step: nothing a first look reads");
  }

  for (int axis = 0; axis < 3; ++axis) {
    std::optional<std::size_t> up, down;
    for (std::size_t k = 0; k < look.positions.size(); ++k) {
      if (look.positions[k].axis != axis) continue;
      auto& slot = look.positions[k].sign > 0 ? up : down;
      if (!slot) slot = k;
    }
    if (!up || !down) continue;
    const double u = look.positions[*up].accel_mps2[axis];
    const double d = look.positions[*down].accel_mps2[axis];
    look.accel.push_back(
        {axis, *up, *down, 0.5 * (u + d), ((u - d) / (2.0 * look.gravity_mps2) - 1.0) * 1e6});
  }

  if (const auto pair = cw_ccw_pair(rates))
    look.rate_test = rate_test(setup, pair->first, pair->second);

  if (!look.thermal.empty()) {
    const auto telemetry = runs.chamber_telemetry(run);
    for (std::size_t k = 0; k < look.thermal.size(); ++k) {
      ThermalMark& mark = look.thermal[k];
      const double start = watch[k].step.started_clock_s.value_or(0.0);
      if (const auto* row = chamber_at(telemetry, start)) {
        mark.air_c = row->air_temperature_c;
        mark.setpoint_c = row->setpoint_c;
      } else {
        mark.air_c = mark.setpoint_c = std::numeric_limits<double>::quiet_NaN();
      }
      mark.imu_rate_c_per_min = k == 0 ? std::numeric_limits<double>::quiet_NaN()
                                       : (mark.imu_c - look.thermal[k - 1].imu_c) /
                                             (mark.t_min - look.thermal[k - 1].t_min);
    }
  }
  return look;
}

}  // namespace calstand::analysis

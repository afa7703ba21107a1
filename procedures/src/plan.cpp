// Plan preview: durations estimated from the station's figures, envelope, station limits.
#include "procedures/plan.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "parameters.hpp"
#include "procedures/pointing.hpp"
#include "references.hpp"

namespace calstand::procedures {
namespace {

using detail::format_number;
using detail::shown_value;

// Angle in [-180, 180) [deg].
double wrap180(double deg) {
  const double w = std::fmod(deg + 180.0, 360.0);
  return (w < 0 ? w + 360.0 : w) - 180.0;
}

// Peak |rate| of a rest-to-rest trapezoidal move [deg/s].
double move_peak_rate(double distance_deg, const core::AxisConfig& a) {
  return std::min(a.max_rate_dps, std::sqrt(distance_deg * a.max_accel_dps2));
}

// The chamber as the plan sees it: a setpoint approached linearly at the ramp rate (no lag).
struct ChamberTrack {
  double from_c = 0.0;
  double to_c = 0.0;
  double start_s = 0.0;
  double ramp_c_per_s = 1.0;

  double at(double t_s) const {
    const double change = ramp_c_per_s * std::max(0.0, t_s - start_s);
    return to_c >= from_c ? std::min(to_c, from_c + change) : std::max(to_c, from_c - change);
  }
};

// The table as the plan sees it: angles [deg] and the rate of an axis left turning [deg/s].
struct AxisTrack {
  double angle_deg = 0.0;
  double rate_dps = 0.0;
};

class Planner {
 public:
  Planner(const core::StationConfig& station, Plan& plan) : station_(station), plan_(plan) {
    chamber_.from_c = chamber_.to_c = station.chamber.ambient_c;
  }

  void run() {
    double t = 0.0;
    for (const Step& s : plan_.steps) {
      // A step with a broken value (already a violation) must not move time backwards.
      const double d = std::max(0.0, duration(s, t));
      plan_.step_start_s.push_back(t);
      plan_.step_duration_s.push_back(d);
      t += d;
    }
    plan_.total_s = t;
  }

 private:
  const core::AxisConfig& axis_config(const std::string& axis) const {
    return axis == "inner" ? station_.table.inner : station_.table.outer;
  }
  AxisEnvelope& axis_envelope(const std::string& axis) {
    return axis == "inner" ? plan_.envelope.inner : plan_.envelope.outer;
  }
  AxisTrack& axis_track(const std::string& axis) { return axis == "inner" ? inner_ : outer_; }

  void violation(const Step& s, const std::string& field, std::string message) {
    plan_.violations.push_back({s.origin_path + "." + field, std::move(message)});
  }

  double duration(const Step& s, double t) {
    switch (s.kind) {
      case StepKind::kSetTemperature:
        return set_temperature(s, t);
      case StepKind::kMove:
        return move(s);
      case StepKind::kRate:
        return rate(s);
      case StepKind::kCapture:
        plan_.envelope.capture_s += s.duration_s;
        ++plan_.envelope.captures;
        return s.duration_s;
      case StepKind::kWait:
        return s.duration_s;
      case StepKind::kPower:
        power(s);
        return s.settle_s;
      case StepKind::kOscillate:
        return oscillate(s);
    }
    return 0.0;
  }

  double set_temperature(const Step& s, double t) {
    const auto& c = station_.chamber;
    if (s.target_c < c.min_c || s.target_c > c.max_c) {
      violation(s, "target_c",
                fmt::format("{} is outside the chamber range [{}, {}]",
                            shown_value(s, "target_c", s.target_c), format_number(c.min_c),
                            format_number(c.max_c)));
    }
    const double ramp = s.ramp_c_per_min.value_or(c.max_ramp_c_per_min);
    if (s.ramp_c_per_min && ramp > c.max_ramp_c_per_min) {
      violation(
          s, "ramp_c_per_min",
          fmt::format("{} exceeds the chamber ramp limit {}",
                      shown_value(s, "ramp_c_per_min", ramp), format_number(c.max_ramp_c_per_min)));
    }
    auto& env = plan_.envelope;
    env.min_temperature_c = std::min(env.min_temperature_c.value_or(s.target_c), s.target_c);
    env.max_temperature_c = std::max(env.max_temperature_c.value_or(s.target_c), s.target_c);
    env.max_ramp_c_per_min = std::max(env.max_ramp_c_per_min, ramp);

    const double now_c = chamber_.at(t);
    chamber_ = {now_c, s.target_c, t, ramp / 60.0};
    if (!s.wait_for_soak || ramp <= 0) return 0.0;
    return std::abs(s.target_c - now_c) / chamber_.ramp_c_per_s + s.soak.stable_s;
  }

  // A power step needs a supply for its unit (or, for all, for at least one).
  void power(const Step& s) {
    if (!s.imu.empty()) {
      if (station_.supply_of(s.imu) == nullptr) {
        violation(s, "imu", fmt::format("the station has no power supply for IMU \"{}\"", s.imu));
      }
    } else if (station_.power_supplies.empty()) {
      violation(s, "power", "the station has no power supply (station file power_supplies)");
    }
  }

  double move(const Step& s) {
    double longest = 0.0, settle = 0.0;
    for (const auto& [name, target] : {std::pair<std::string, double>{"outer", s.outer_deg},
                                       std::pair<std::string, double>{"inner", s.inner_deg}}) {
      AxisTrack& track = axis_track(name);
      const core::AxisConfig& cfg = axis_config(name);
      const double distance = std::abs(wrap180(target - track.angle_deg));
      track.angle_deg = wrap180(target);
      if (distance == 0.0) continue;
      longest = std::max(longest, trapezoid_move_s(distance, cfg.max_rate_dps, cfg.max_accel_dps2));
      settle = std::max(settle, cfg.settle_time_s);
      AxisEnvelope& env = axis_envelope(name);
      env.max_move_rate_dps = std::max(env.max_move_rate_dps, move_peak_rate(distance, cfg));
      env.max_accel_dps2 = std::max(env.max_accel_dps2, cfg.max_accel_dps2);
    }
    return longest + settle;
  }

  double rate(const Step& s) {
    const core::AxisConfig& cfg = axis_config(s.axis);
    if (std::abs(s.rate_dps) > cfg.max_rate_dps) {
      violation(
          s, "rate_dps",
          fmt::format("{} exceeds the {} axis limit {}", shown_value(s, "rate_dps", s.rate_dps),
                      s.axis, format_number(cfg.max_rate_dps)));
    }
    AxisEnvelope& env = axis_envelope(s.axis);
    env.max_rate_dps = std::max(env.max_rate_dps, std::abs(s.rate_dps));
    env.max_accel_dps2 = std::max(env.max_accel_dps2, cfg.max_accel_dps2);
    plan_.envelope.capture_s += s.duration_s;
    ++plan_.envelope.captures;

    AxisTrack& track = axis_track(s.axis);
    const double accel_s = std::abs(s.rate_dps - track.rate_dps) / cfg.max_accel_dps2;
    const double stop_s = s.rest_after ? std::abs(s.rate_dps) / cfg.max_accel_dps2 : 0.0;
    const double turned_deg = 0.5 * (track.rate_dps + s.rate_dps) * accel_s +
                              s.rate_dps * (s.settle_s + s.duration_s) + 0.5 * s.rate_dps * stop_s;
    track.angle_deg = wrap180(track.angle_deg + turned_deg);
    track.rate_dps = s.rest_after ? 0.0 : s.rate_dps;
    return accel_s + s.settle_s + s.duration_s + stop_s;
  }

  // The sine's peak rate and acceleration are the axis's own limits to respect: a controller
  // refuses (or worse, clips) a sine beyond them, and a clipped sine is no sine to fit.
  double oscillate(const Step& s) {
    const core::AxisConfig& cfg = axis_config(s.axis);
    const double peak_rate = s.peak_rate_dps();
    const double peak_accel = s.peak_accel_dps2();
    if (peak_rate > cfg.max_rate_dps) {
      violation(s, "amplitude_deg",
                fmt::format("{} deg at {} Hz peaks at {} deg/s (2 pi f A), above the {} axis "
                            "rate limit {} deg/s",
                            shown_value(s, "amplitude_deg", s.amplitude_deg),
                            shown_value(s, "frequency_hz", s.frequency_hz),
                            format_number(peak_rate), s.axis, format_number(cfg.max_rate_dps)));
    }
    if (peak_accel > cfg.max_accel_dps2) {
      violation(s, "amplitude_deg",
                fmt::format("{} deg at {} Hz peaks at {} deg/s^2 ((2 pi f)^2 A), above the {} "
                            "axis acceleration limit {} deg/s^2",
                            shown_value(s, "amplitude_deg", s.amplitude_deg),
                            shown_value(s, "frequency_hz", s.frequency_hz),
                            format_number(peak_accel), s.axis, format_number(cfg.max_accel_dps2)));
    }
    AxisEnvelope& env = axis_envelope(s.axis);
    env.max_rate_dps = std::max(env.max_rate_dps, peak_rate);
    env.max_accel_dps2 = std::max(env.max_accel_dps2, peak_accel);
    plan_.envelope.capture_s += s.duration_s;
    ++plan_.envelope.captures;
    // The axis comes back to its start angle and settles there.
    return s.frequency_hz > 0 ? s.settle_cycles / s.frequency_hz + s.duration_s + cfg.settle_time_s
                              : 0.0;
  }

  const core::StationConfig& station_;
  Plan& plan_;
  ChamberTrack chamber_;
  AxisTrack outer_;
  AxisTrack inner_;
};

// Fills in the angles of every move given by pointing (`up`), for the station's table and the
// named (or first) IMU's mount; a pointing the table cannot make is a violation of that step.
void resolve_pointings(const core::StationConfig& station, Plan& plan) {
  for (Step& s : plan.steps) {
    if (s.kind != StepKind::kMove || s.up.empty()) continue;
    std::size_t imu = 0;
    if (!s.imu.empty()) {
      const auto it = std::find_if(station.imus.begin(), station.imus.end(),
                                   [&](const core::ImuConfig& c) { return c.name == s.imu; });
      if (it == station.imus.end()) {
        plan.violations.push_back(
            {s.origin_path + ".imu",
             fmt::format("\"{}\" is not an IMU of station \"{}\"", s.imu, station.name)});
        continue;
      }
      imu = static_cast<std::size_t>(it - station.imus.begin());
    }
    if (station.imus.empty()) {
      plan.violations.push_back({s.origin_path + ".up", "the station has no IMU to point"});
      continue;
    }
    const auto direction = parse_body_direction(s.up);
    const core::TableGeometry geometry = station.geometry(imu);
    const auto angles = direction ? point_up(geometry, *direction) : std::nullopt;
    if (!angles) {
      const auto& o = geometry.outer_axis;
      const auto& i = geometry.inner_axis;
      plan.violations.push_back(
          {s.origin_path + ".up",
           fmt::format("the table cannot point body axis {} up: no outer and inner angles in "
                       "steps of 45 deg put it along the vertical (outer axis [{:g} {:g} {:g}], "
                       "inner axis [{:g} {:g} {:g}], with the mount of IMU \"{}\")",
                       s.up, o.x(), o.y(), o.z(), i.x(), i.y(), i.z(), station.imus[imu].name)});
      continue;
    }
    s.outer_deg = angles->outer_deg;
    s.inner_deg = angles->inner_deg;
  }
}

nlohmann::json axis_json(const AxisEnvelope& a) {
  return {{"max_rate_dps", a.max_rate_dps},
          {"max_move_rate_dps", a.max_move_rate_dps},
          {"max_accel_dps2", a.max_accel_dps2}};
}

}  // namespace

double trapezoid_move_s(double distance_deg, double max_rate_dps, double max_accel_dps2) {
  if (distance_deg <= 0.0) return 0.0;
  const double ramp_deg = max_rate_dps * max_rate_dps / max_accel_dps2;  // to full rate and back
  if (distance_deg >= ramp_deg) return distance_deg / max_rate_dps + max_rate_dps / max_accel_dps2;
  return 2.0 * std::sqrt(distance_deg / max_accel_dps2);
}

nlohmann::json Envelope::to_json() const {
  nlohmann::json j = {{"outer", axis_json(outer)},
                      {"inner", axis_json(inner)},
                      {"max_ramp_c_per_min", max_ramp_c_per_min},
                      {"capture_s", capture_s},
                      {"captures", captures}};
  j["min_temperature_c"] = min_temperature_c ? nlohmann::json(*min_temperature_c) : nullptr;
  j["max_temperature_c"] = max_temperature_c ? nlohmann::json(*max_temperature_c) : nullptr;
  return j;
}

nlohmann::json Plan::to_json() const {
  nlohmann::json j_steps = nlohmann::json::array();
  for (std::size_t i = 0; i < steps.size(); ++i) {
    nlohmann::json s = steps[i].to_json();
    s["estimated_start_s"] = step_start_s.at(i);
    s["estimated_duration_s"] = step_duration_s.at(i);
    j_steps.push_back(std::move(s));
  }
  nlohmann::json j_violations = nlohmann::json::array();
  for (const auto& v : violations)
    j_violations.push_back({{"path", v.path}, {"message", v.message}});
  return {{"procedure", procedure},      {"file", file_name},  {"parameters", parameters},
          {"steps", std::move(j_steps)}, {"total_s", total_s}, {"envelope", envelope.to_json()},
          {"violations", j_violations},  {"ok", ok()}};
}

Plan make_plan(const Procedure& procedure, const core::StationConfig& station,
               const Overrides& overrides) {
  Plan plan;
  plan.procedure = procedure.name;
  plan.file_name = procedure.file_name;
  std::vector<Violation> ignored;  // reported by expand_collecting below
  plan.parameters = detail::resolve_parameters_collecting(procedure, overrides, ignored);
  plan.steps = expand_collecting(procedure, overrides, plan.violations);
  resolve_pointings(station, plan);
  Planner(station, plan).run();
  // Every value may be in range and the whole still absurd (a capture of 1e308 s): a run that
  // would never end is refused here, not left to spin in the engine.
  if (!std::isfinite(plan.total_s) || plan.total_s > kMaxPlanDuration_s) {
    plan.violations.push_back(
        {"procedure",
         fmt::format("the plan takes {:.3g} s of station time, more than a year ({:.3g} s): "
                     "a duration or a count is out of proportion",
                     plan.total_s, kMaxPlanDuration_s)});
  }
  return plan;
}

void require_valid(const Plan& plan) {
  if (!plan.ok()) throw ProcedureError(plan.file_name, plan.violations);
}

}  // namespace calstand::procedures

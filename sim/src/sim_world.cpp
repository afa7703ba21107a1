#include "sim/sim_world.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::sim {
namespace {

ChamberParams chamber_params(const core::ChamberConfig& c) {
  ChamberParams p;
  p.min_c = c.min_c;
  p.max_c = c.max_c;
  p.max_ramp_c_per_min = c.max_ramp_c_per_min;
  p.ambient_c = c.ambient_c;
  p.air_time_constant_s = c.air_time_constant_s;
  p.control_noise_c = c.control_noise_c;
  p.control_noise_tau_s = c.control_noise_tau_s;
  p.imu_time_constant_s = c.imu_time_constant_s;
  p.imu_self_heating_c = c.imu_self_heating_c;
  return p;
}

void require_sim(const std::string& backend, const std::string& field) {
  if (backend != "sim") {
    throw core::InputError(field, fmt::format("backend \"{}\" is not simulated; the simulated "
                                              "world needs \"sim\"",
                                              backend));
  }
}

}  // namespace

core::StationConfig default_station() {
  const auto text = builtin_file("default.json");
  if (!text) throw std::logic_error("sim/stations/default.json is not compiled in");
  return core::StationConfig::from_json(core::parse_json_text(*text, "<built-in station>"),
                                        "<built-in station>");
}

core::StationConfig load_station_or_default(const std::string& path) {
  return path.empty() ? default_station() : core::StationConfig::load(path);
}

ImuTruth resolve_imu_truth(const core::ImuConfig& imu, std::uint64_t station_seed,
                           std::size_t index) {
  const std::uint64_t draw_seed = derive_seed(station_seed, "imu-unit-" + imu.name, index);
  ImuTruth truth;
  if (!imu.model.empty()) {
    const auto spec = builtin_spec(imu.model);
    if (!spec) {
      std::string known;
      for (const auto& n : builtin_spec_names()) known += (known.empty() ? "" : ", ") + n;
      throw core::InputError(
          fmt::format("imus[{}].model", index),
          fmt::format("unknown built-in model \"{}\" (known: {})", imu.model, known));
    }
    truth = truth_from_spec(*spec, "<built-in " + imu.model + ">", draw_seed);
  } else if (!imu.spec_file.empty()) {
    truth = truth_from_spec(core::read_json_file(imu.spec_file), imu.spec_file, draw_seed);
  } else if (!imu.truth_file.empty()) {
    truth = imu_truth_from_json(core::read_json_file(imu.truth_file), imu.truth_file);
  } else {
    truth = imu_truth_from_json(imu.truth, fmt::format("imus[{}].truth", index));
  }
  truth.name = imu.name;
  return truth;
}

std::uint64_t noise_seed(std::uint64_t station_seed, std::uint64_t stream) {
  return stream == 0 ? station_seed : derive_seed(station_seed, "noise-stream", stream);
}

std::unique_ptr<ImuSim> make_imu_sim(const core::StationConfig& config, std::size_t index,
                                     std::uint64_t noise_stream) {
  ImuTruth truth = resolve_imu_truth(config.imus.at(index), config.seed, index);
  try {
    return std::make_unique<ImuSim>(
        std::move(truth), config.geometry(index), config.site, config.table.tilt_rad,
        derive_seed(noise_seed(config.seed, noise_stream), "imu-noise", index));
  } catch (const std::invalid_argument& e) {
    throw core::InputError(fmt::format("imus[{}]", index), e.what());
  }
}

SimWorld::SimWorld(const core::StationConfig& config, double start_time_s,
                   std::uint64_t noise_stream)
    : config_(config),
      clock_(start_time_s),
      table_(config.table.outer, config.table.inner),
      chamber_(chamber_params(config.chamber),
               derive_seed(noise_seed(config.seed, noise_stream), "chamber")) {
  require_sim(config.table.backend, "table.backend");
  require_sim(config.chamber.backend, "chamber.backend");
  for (std::size_t i = 0; i < config.imus.size(); ++i) {
    const auto& c = config.imus[i];
    require_sim(c.backend, fmt::format("imus[{}].backend", i));
    SimulatedImu imu;
    imu.name = c.name;
    imu.sim = make_imu_sim(config, i, noise_stream);
    // A world starts (or a run resumes) with its units on for long: warm and settled.
    imu.sim->power_on(start_time_s, /*warm=*/true);
    imu.self_heating_c = config.chamber.imu_self_heating_c;
    // A sample stands for the interval that ends at its time stamp: the first is one period
    // after power-up, so advancing by T delivers T * rate samples.
    imu.first_sample_s = start_time_s + imu.sim->sample_period_s();
    imus_.push_back(std::move(imu));
  }
}

void SimWorld::power_cycle_imu(std::size_t i) {
  SimulatedImu& imu = imus_.at(i);
  imu.sim->power_off();
  imu.sim->power_on(clock_.now_s());
  // The first sample after power-up falls one period later, on a fresh grid.
  imu.first_sample_s = clock_.now_s() + imu.sim->sample_period_s();
  imu.next_index = 0;
}

void SimWorld::set_imu_power(std::size_t i, bool on) {
  SimulatedImu& imu = imus_.at(i);
  if (on == imu.sim->powered()) return;
  if (!on) {
    imu.sim->power_off();
    return;
  }
  imu.sim->power_on(clock_.now_s());
  imu.first_sample_s = clock_.now_s() + imu.sim->sample_period_s();
  imu.next_index = 0;
}

double SimWorld::imu_temperature_c(std::size_t i) const {
  return chamber_.imu_temperature_c() -
         (config_.chamber.imu_self_heating_c - imus_.at(i).self_heating_c);
}

TableKinematics SimWorld::table_kinematics() const {
  TableKinematics k;
  k.outer_deg = table_.outer().true_angle_deg();
  k.outer_rate_dps = table_.outer().true_rate_dps();
  k.outer_accel_dps2 = table_.outer().true_accel_dps2();
  k.inner_deg = table_.inner().true_angle_deg();
  k.inner_rate_dps = table_.inner().true_rate_dps();
  k.inner_accel_dps2 = table_.inner().true_accel_dps2();
  return k;
}

std::vector<core::ImuSample> SimWorld::take_samples(std::size_t i) {
  std::vector<core::ImuSample> out;
  out.swap(imus_.at(i).buffer);
  return out;
}

void SimWorld::advance_to(double t_end_s) {
  // Sample instants within this tolerance of the end are produced now, so a caller advancing
  // by whole sample periods never sees a rounding error shift a sample into the next call.
  constexpr double kTimeEps = 1e-9;
  double t = clock_.now_s();
  while (t < t_end_s - kTimeEps) {
    double next = std::min(t_end_s, t + config_.sim_max_step_s);
    for (const auto& imu : imus_) {
      if (imu.sim->powered()) next = std::min(next, imu.next_due_s());
    }
    const double dt = next - t;
    if (dt > 0.0) {
      table_.step(dt);
      // Self-heating of each unit: towards the chamber's figure while on, towards none while
      // off, with the IMU's thermal time constant (exact for any step).
      const double tau = config_.chamber.imu_time_constant_s;
      const double keep = tau > 0.0 ? std::exp(-dt / tau) : 0.0;
      for (auto& imu : imus_) {
        const double goal = imu.sim->powered() ? config_.chamber.imu_self_heating_c : 0.0;
        imu.self_heating_c = goal + (imu.self_heating_c - goal) * keep;
      }
      thermal_pending_s_ += dt;
      if (thermal_pending_s_ >= config_.sim_thermal_step_s) {
        chamber_.step(thermal_pending_s_);
        thermal_pending_s_ = 0.0;
      }
    }
    t = next;
    clock_.advance_to(t);

    TableKinematics kin;
    bool have_kinematics = false;
    for (std::size_t i = 0; i < imus_.size(); ++i) {
      SimulatedImu& imu = imus_[i];
      if (!imu.sim->powered() || imu.next_due_s() > t + kTimeEps) continue;
      if (!have_kinematics) {
        kin = table_kinematics();
        have_kinematics = true;
      }
      const core::ImuSample s = imu.sim->sample(t, kin, imu_temperature_c(i));
      ++imu.next_index;
      if (imu.drop_remaining > 0) {
        --imu.drop_remaining;
        continue;
      }
      if (imu.stalled) continue;
      if (sink_) {
        sink_(i, s);
      } else {
        imu.buffer.push_back(s);
      }
    }
  }
  clock_.advance_to(t_end_s);
}

}  // namespace calstand::sim

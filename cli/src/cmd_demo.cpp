// `calstand demo`: the main job on the embedded simulator. For now a simulated IMU on the
// simulated table, showing what it measures in the classic positions, a CW/CCW rate test and a
// chamber temperature step; later issues grow it into a whole campaign with a fit and a report.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/station_config.hpp"
#include "sim/imu_sim.hpp"
#include "sim/sim_world.hpp"

namespace calstand::cli {
namespace {

using nlohmann::json;

struct DemoOptions {
  std::string station_file;
  std::uint64_t seed = 0;
  bool seed_given = false;
  double capture_s = 10.0;
  bool as_json = false;
};

// Means of one capture: what a static or constant-rate step measures.
struct CaptureMean {
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
  double temperature_c = 0.0;
  std::size_t samples = 0;
  std::size_t sequence_gaps = 0;
};

CaptureMean capture(sim::SimWorld& world, double duration_s) {
  world.take_samples(0);  // discard anything from the motion before
  world.advance(duration_s);
  CaptureMean m;
  const auto samples = world.take_samples(0);
  const auto modulus = world.imu(0).truth().sequence_modulus;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    m.gyro_dps += samples[k].gyro_dps;
    m.accel_mps2 += samples[k].accel_mps2;
    m.temperature_c += samples[k].temperature_c;
    if (k > 0 && samples[k].sequence != (samples[k - 1].sequence + 1) % modulus) ++m.sequence_gaps;
  }
  m.samples = samples.size();
  if (m.samples > 0) {
    const double n = static_cast<double>(m.samples);
    m.gyro_dps /= n;
    m.accel_mps2 /= n;
    m.temperature_c /= n;
  }
  return m;
}

// Commands a position and runs the world until both axes report in position.
void move_and_settle(sim::SimWorld& world, double outer_deg, double inner_deg) {
  auto ok = world.table().outer().command_position(outer_deg);
  if (!ok) throw std::runtime_error("outer axis refused the move: " + ok.message);
  ok = world.table().inner().command_position(inner_deg);
  if (!ok) throw std::runtime_error("inner axis refused the move: " + ok.message);
  const double deadline = world.now_s() + 120.0;
  do {
    world.advance(0.1);
    const auto s = world.table_state();
    if (s.outer.in_position && s.inner.in_position) return;
  } while (world.now_s() < deadline);
  throw std::runtime_error(
      fmt::format("table did not settle at ({}, {}) deg", outer_deg, inner_deg));
}

struct Position {
  std::string label;  // "x up"
  double outer_deg;
  double inner_deg;
  int axis;  // body axis along the vertical
  int sign;  // +1 up, -1 down
};

// The first table angles (outer, inner), searched over multiples of 90 deg and then 45 deg,
// that point body axis `axis` up (sign +1) or down (-1): C_LB^T (0, 0, 1) = sign e_axis within
// 1e-6. Throws when none does: the table's axes and the IMU mount decide which pointings exist.
Position find_position(const core::TableGeometry& geometry, int axis, int sign) {
  const char name = static_cast<char>('x' + axis);
  const Eigen::Vector3d want = sign * Eigen::Vector3d::Unit(axis);
  for (const double step : {90.0, 45.0}) {
    // Candidate (outer, inner) pairs, the smallest total move from zero first.
    std::vector<std::pair<double, double>> pairs;
    for (double outer = -180.0 + step; outer <= 180.0; outer += step) {
      for (double inner = -180.0 + step; inner <= 180.0; inner += step) {
        pairs.emplace_back(outer, inner);
      }
    }
    std::stable_sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
      return std::abs(a.first) + std::abs(a.second) < std::abs(b.first) + std::abs(b.second);
    });
    for (const auto& [outer, inner] : pairs) {
      const Eigen::Vector3d up_in_body =
          geometry.body_to_level(outer, inner).transpose() * Eigen::Vector3d::UnitZ();
      if ((up_in_body - want).norm() < 1e-6) {
        return {fmt::format("{} {}", name, sign > 0 ? "up" : "down"), outer, inner, axis, sign};
      }
    }
  }
  const auto& o = geometry.outer_axis;
  const auto& i = geometry.inner_axis;
  throw std::runtime_error(fmt::format(
      "the table cannot point body axis {}{} {}: no outer and inner angles in steps of 45 deg "
      "put it along the vertical (outer axis [{:g} {:g} {:g}], inner axis [{:g} {:g} {:g}] with "
      "this IMU's mount); the demo needs every body axis up and down",
      sign > 0 ? '+' : '-', name, sign > 0 ? "up" : "down", o.x(), o.y(), o.z(), i.x(), i.y(),
      i.z()));
}

// Each body axis up and down, in the order z, x, y, found for this station's table and mount.
std::vector<Position> six_positions(const core::TableGeometry& geometry) {
  std::vector<Position> positions;
  for (const int axis : {2, 0, 1}) {
    for (const int sign : {+1, -1}) positions.push_back(find_position(geometry, axis, sign));
  }
  return positions;
}

std::string vec_text(const Eigen::Vector3d& v, const char* format) {
  return fmt::format(fmt::runtime(fmt::format("{0} {0} {0}", format)), v.x(), v.y(), v.z());
}

int run_demo(const DemoOptions& opt) {
  if (!(opt.capture_s > 0.0 && opt.capture_s <= 3600.0)) {
    throw core::InputError("--capture",
                           fmt::format("must be in (0, 3600] s, got {}", opt.capture_s));
  }
  core::StationConfig station = sim::load_station_or_default(opt.station_file);
  if (opt.seed_given) station.seed = opt.seed;
  const core::TableGeometry geometry = station.geometry(0);
  const std::vector<Position> six_pos = six_positions(geometry);  // before any lab time

  const auto wall_start = std::chrono::steady_clock::now();
  sim::SimWorld world(station);
  const sim::ImuTruth& truth = world.imu(0).truth();
  const double g = station.site.gravity();
  const Eigen::Vector3d earth_dph =
      station.site.earth_rate_level_radps() * core::kRadToDeg * 3600.0;

  json report;
  report["station"] = station.name;
  // The turn-on biases drawn at this power-up: simulator truth, like the noise-free columns.
  const Eigen::Vector3d turn_on_gyro_dph = world.imu(0).turn_on_gyro_bias() * 3600.0;
  const Eigen::Vector3d turn_on_accel = world.imu(0).turn_on_accel_bias();
  report["imu"] = {
      {"name", world.imu_name(0)},
      {"sample_rate_hz", truth.sample_rate_hz},
      {"turn_on_gyro_bias_dph", {turn_on_gyro_dph.x(), turn_on_gyro_dph.y(), turn_on_gyro_dph.z()}},
      {"turn_on_accel_bias_mps2", {turn_on_accel.x(), turn_on_accel.y(), turn_on_accel.z()}}};
  report["site"] = {{"latitude_deg", station.site.latitude_deg}, {"gravity_mps2", g}};

  if (!opt.as_json) {
    fmt::print(
        "calstand demo: station \"{}\", IMU \"{}\" ({:.0f} Hz), latitude {:.4f} deg, "
        "g = {:.5f} m/s^2, Earth rate N {:.3f} U {:.3f} deg/h\n\n",
        station.name, world.imu_name(0), truth.sample_rate_hz, station.site.latitude_deg, g,
        earth_dph.y(), earth_dph.z());
    fmt::print("Six positions, {:.0f} s static capture each after the table settles\n",
               opt.capture_s);
    fmt::print("{:<7} {:>6} {:>6}  {:>29}  {:>32}  {:>7}\n", "pos", "outer", "inner",
               "gyro x y z [deg/h]", "accel x y z [m/s^2]", "T [degC]");
  }

  // What a noise-free copy of this IMU (same errors, same turn-on bias) reads at a position, at
  // the IMU temperature the capture measured so that temperature terms match too: the
  // simulator's truth, which a real station would not know.
  auto noise_free_accel = [&](const Position& p, double temperature_c) {
    sim::TableKinematics k;
    k.outer_deg = p.outer_deg;
    k.inner_deg = p.inner_deg;
    const sim::ImuInputs in =
        sim::imu_inputs(truth, geometry, station.site, station.table.tilt_rad, k, temperature_c);
    return Eigen::Vector3d(in.force_mps2 + sim::deterministic_errors(truth, in).second +
                           world.imu(0).turn_on_accel_bias());
  };

  // 1. Six positions: each body axis up and down.
  std::vector<CaptureMean> six;
  json positions = json::array();
  for (const Position& p : six_pos) {
    move_and_settle(world, p.outer_deg, p.inner_deg);
    const CaptureMean m = capture(world, opt.capture_s);
    six.push_back(m);
    const Eigen::Vector3d gyro_dph = m.gyro_dps * 3600.0;
    const Eigen::Vector3d noise_free = noise_free_accel(p, m.temperature_c);
    positions.push_back(
        {{"position", p.label},
         {"outer_deg", p.outer_deg},
         {"inner_deg", p.inner_deg},
         {"gyro_dph", {gyro_dph.x(), gyro_dph.y(), gyro_dph.z()}},
         {"accel_mps2", {m.accel_mps2.x(), m.accel_mps2.y(), m.accel_mps2.z()}},
         {"noise_free_accel_mps2", {noise_free.x(), noise_free.y(), noise_free.z()}},
         {"temperature_c", m.temperature_c},
         {"samples", m.samples}});
    if (!opt.as_json) {
      fmt::print("{:<7} {:>6.1f} {:>6.1f}  {:>29}  {:>32}  {:>7.2f}\n", p.label, p.outer_deg,
                 p.inner_deg, vec_text(gyro_dph, "{:9.3f}"), vec_text(m.accel_mps2, "{:10.5f}"),
                 m.temperature_c);
    }
  }
  report["six_position"] = positions;

  // What the up/down pairs say about each accelerometer (the seed's two-position method),
  // beside what a noise-free copy of this IMU would give by the same method: the simulator's
  // truth, which a real station would not know. The pair's "bias" also holds the quadratic
  // term's g^2 share, so the truth column is computed through the same formula, not read off.
  json accel_rows = json::array();
  if (!opt.as_json) {
    fmt::print(
        "\nAccelerometers from the up/down pairs: bias = (up + down) / 2, "
        "scale = (up - down) / 2g - 1\n");
    fmt::print("{:<5} {:>14} {:>14} {:>12} {:>12}\n", "axis", "bias [mg]", "noise-free",
               "scale [ppm]", "noise-free");
  }
  for (int axis = 0; axis < 3; ++axis) {
    const CaptureMean* up = nullptr;
    const CaptureMean* down = nullptr;
    const Position* p_up = nullptr;
    const Position* p_down = nullptr;
    for (std::size_t k = 0; k < six.size(); ++k) {
      if (six_pos[k].axis != axis) continue;
      if (six_pos[k].sign > 0) {
        up = &six[k];
        p_up = &six_pos[k];
      } else {
        down = &six[k];
        p_down = &six_pos[k];
      }
    }
    auto bias_of = [&](double u, double d) { return 0.5 * (u + d); };
    auto scale_of = [&](double u, double d) { return ((u - d) / (2.0 * g) - 1.0) * 1e6; };
    const double bias = bias_of(up->accel_mps2[axis], down->accel_mps2[axis]);
    const double scale_ppm = scale_of(up->accel_mps2[axis], down->accel_mps2[axis]);
    const double ref_up = noise_free_accel(*p_up, up->temperature_c)[axis];
    const double ref_down = noise_free_accel(*p_down, down->temperature_c)[axis];
    const double ref_bias = bias_of(ref_up, ref_down);
    const double ref_scale = scale_of(ref_up, ref_down);
    const double mg = 1e3 / core::kStandardGravity;
    const char name = static_cast<char>('x' + axis);
    accel_rows.push_back({{"axis", std::string(1, name)},
                          {"bias_mps2", bias},
                          {"noise_free_bias_mps2", ref_bias},
                          {"scale_ppm", scale_ppm},
                          {"noise_free_scale_ppm", ref_scale}});
    if (!opt.as_json) {
      fmt::print("{:<5} {:>14.4f} {:>14.4f} {:>12.1f} {:>12.1f}\n", name, bias * mg, ref_bias * mg,
                 scale_ppm, ref_scale);
    }
  }
  report["accel_two_position"] = accel_rows;

  // 2. Rate test about the inner axis at the z-up position: CW and CCW, whole revolutions. The
  // body axis most nearly along the inner axis measures it; over whole revolutions the Earth
  // rate's part across the inner axis averages out, so its mean is the reference rate
  // C_BL (w_table + w_ie) on that axis. The difference of the two means cancels the bias and
  // the Earth rate and leaves the scale factor.
  const Position& level = six_pos.front();  // z up
  move_and_settle(world, level.outer_deg, level.inner_deg);
  const Eigen::Vector3d inner_in_body =
      geometry.body_to_level(level.outer_deg, level.inner_deg).transpose() *
      geometry.table_rate_level_dps(level.outer_deg, 0.0, 1.0);
  int rate_axis = 0;
  inner_in_body.cwiseAbs().maxCoeff(&rate_axis);
  const char rate_axis_name = static_cast<char>('x' + rate_axis);
  const double rate_dps = 100.0;
  const double revolutions_s = 10.0 * 360.0 / rate_dps;
  json rate_rows = json::array();
  double measured[2] = {0.0, 0.0};
  double expected[2] = {0.0, 0.0};
  const double signs[2] = {+1.0, -1.0};
  for (int k = 0; k < 2; ++k) {
    const auto ok = world.table().inner().command_rate(signs[k] * rate_dps);
    if (!ok) throw std::runtime_error("inner axis refused the rate: " + ok.message);
    // Let the rate settle before capturing.
    const double deadline = world.now_s() + 60.0;
    do world.advance(0.1);
    while (!world.table_state().inner.in_position && world.now_s() < deadline);
    const CaptureMean m = capture(world, revolutions_s);
    measured[k] = m.gyro_dps[rate_axis];
    sim::TableKinematics kin;
    kin.outer_deg = level.outer_deg;
    kin.inner_deg = level.inner_deg;
    kin.inner_rate_dps = signs[k] * rate_dps;
    expected[k] =
        sim::imu_inputs(truth, geometry, station.site, station.table.tilt_rad, kin, m.temperature_c)
            .rate_dps[rate_axis];
    rate_rows.push_back({{"rate_dps", signs[k] * rate_dps},
                         {"gyro_dps", measured[k]},
                         {"expected_dps", expected[k]}});
  }
  world.table().inner().stop();
  const double scale_ppm = ((measured[0] - measured[1]) / (expected[0] - expected[1]) - 1.0) * 1e6;
  const double bias_dph =
      0.5 * ((measured[0] + measured[1]) - (expected[0] + expected[1])) * 3600.0;
  const double true_bias_dph =
      (truth.gyro_bias[rate_axis] + world.imu(0).turn_on_gyro_bias()[rate_axis]) * 3600.0;
  report["rate_test"] = {{"axis", std::string(1, rate_axis_name)},
                         {"outer_deg", level.outer_deg},
                         {"inner_deg", level.inner_deg},
                         {"rows", rate_rows},
                         {"gyro_scale_ppm", scale_ppm},
                         {"true_gyro_scale_ppm", truth.gyro_scale[rate_axis]},
                         {"gyro_bias_dph", bias_dph},
                         {"true_gyro_bias_dph", true_bias_dph}};
  if (!opt.as_json) {
    fmt::print(
        "\nRate test about the inner axis at the z-up position (outer {:.1f}, inner {:.1f} "
        "deg), body axis {}{} along it, 10 revolutions each way\n",
        level.outer_deg, level.inner_deg, inner_in_body[rate_axis] > 0 ? '+' : '-', rate_axis_name);
    fmt::print("{:>10} {:>18} {:>22}\n", "rate", fmt::format("gyro {} [deg/s]", rate_axis_name),
               "table+Earth [deg/s]");
    for (const auto& r : rate_rows) {
      fmt::print("{:>10.1f} {:>18.6f} {:>22.6f}\n", r["rate_dps"].get<double>(),
                 r["gyro_dps"].get<double>(), r["expected_dps"].get<double>());
    }
    fmt::print(
        "gyro {0} scale error from CW/CCW: {1:.1f} ppm (truth {2:.1f} ppm); "
        "bias after removing Earth rate: {3:.3f} deg/h (truth {4:.3f} deg/h)\n",
        rate_axis_name, scale_ppm, truth.gyro_scale[rate_axis], bias_dph, true_bias_dph);
  }

  // 3. Chamber step: the IMU's own temperature lags the air.
  const double target_c = std::min(45.0, station.chamber.max_c);
  const auto ok = world.chamber().set_setpoint(target_c);
  if (!ok) throw std::runtime_error("chamber refused the setpoint: " + ok.message);
  json thermal = json::array();
  if (!opt.as_json) {
    fmt::print("\nChamber to {:.0f} degC at {:.1f} degC/min; the IMU follows the air with a lag\n",
               target_c, station.chamber.max_ramp_c_per_min);
    fmt::print("{:>8} {:>10} {:>10} {:>12}\n", "t [min]", "air [C]", "IMU [C]", "IMU [C/min]");
  }
  const double t0 = world.now_s();
  for (double minutes : {0.0, 5.0, 10.0, 20.0, 40.0, 60.0, 90.0}) {
    world.advance_to(t0 + minutes * 60.0);
    world.take_samples(0);
    const double air = world.chamber().air_temperature_c();
    const double imu = world.chamber().imu_temperature_c();
    const double rate = world.chamber().imu_temperature_rate_c_per_min();
    thermal.push_back(
        {{"t_min", minutes}, {"air_c", air}, {"imu_c", imu}, {"imu_rate_c_per_min", rate}});
    if (!opt.as_json)
      fmt::print("{:>8.0f} {:>10.2f} {:>10.2f} {:>12.3f}\n", minutes, air, imu, rate);
  }
  world.chamber().standby();
  report["thermal_step"] = thermal;

  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  report["simulated_s"] = world.now_s();
  report["wall_s"] = wall_s;
  if (opt.as_json) {
    fmt::print("{}\n", report.dump(2));
  } else {
    fmt::print("\nSimulated {:.2f} h of lab time in {:.2f} s of wall time ({:.0f}x real time).\n",
               world.now_s() / 3600.0, wall_s, world.now_s() / std::max(wall_s, 1e-9));
  }
  return 0;
}

}  // namespace

void register_demo(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "Run the main job on the embedded simulator: a simulated IMU on the simulated "
      "table in the six positions, a CW/CCW rate test and a chamber step");
  cmd->add_option("--station", opt->station_file, "Station file (default: built-in simulator)");
  cmd->add_option("--seed", opt->seed, "Override the station seed")
      ->each([opt](const std::string&) { opt->seed_given = true; });
  cmd->add_option("--capture", opt->capture_s, "Static capture per position [s], in (0, 3600]")
      ->capture_default_str();
  cmd->add_flag("--json", opt->as_json, "Machine-readable output");
  cmd->callback([opt] { run_demo(*opt); });
}

}  // namespace calstand::cli

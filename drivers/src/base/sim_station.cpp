#include "drivers/sim_station.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.hpp"
#include "drivers/device_support.hpp"

namespace calstand::drivers {
namespace {

// The simulated devices have no link to open: configure() only moves the lifecycle.
class SimLifecycle : public Lifecycle {
 public:
  Result configure() {
    set(DeviceState::kInactive);
    return Result::success();
  }
  Result deactivate() {
    Lifecycle::deactivate();
    return Result::success();
  }
};

Result from_sim(const sim::Status& s) {
  return s.ok ? Result::success() : Result::failure(s.message);
}

}  // namespace

class SimStation::SimTurntable final : public Turntable {
 public:
  explicit SimTurntable(sim::SimWorld& world) : world_(world) {}
  const std::string& name() const override { return name_; }
  Result configure() override { return life_.configure(); }
  Result activate() override { return life_.activate(); }
  Result deactivate() override {
    world_.table().outer().stop();
    world_.table().inner().stop();
    return life_.deactivate();
  }
  DeviceState state() const override { return life_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override {
    return {{"refused_commands", refused_}};
  }
  Result move_to(double outer_deg, double inner_deg) override {
    if (auto r = life_.require_active(name_); !r) return r;
    auto r = count(from_sim(world_.table().outer().command_position(outer_deg)));
    if (!r) return Result::failure("outer axis: " + r.message);
    r = count(from_sim(world_.table().inner().command_position(inner_deg)));
    if (!r) return Result::failure("inner axis: " + r.message);
    return r;
  }
  Result set_rate(TableAxis axis, double rate_dps) override {
    if (auto r = life_.require_active(name_); !r) return r;
    auto& a = axis == TableAxis::kOuter ? world_.table().outer() : world_.table().inner();
    const auto r = count(from_sim(a.command_rate(rate_dps)));
    if (!r)
      return Result::failure(
          fmt::format("{} axis: {}", axis == TableAxis::kOuter ? "outer" : "inner", r.message));
    return r;
  }
  Result start_sine(TableAxis axis, double amplitude_deg, double frequency_hz) override {
    if (auto r = life_.require_active(name_); !r) return r;
    auto& a = axis == TableAxis::kOuter ? world_.table().outer() : world_.table().inner();
    const auto r = count(from_sim(a.command_sine(amplitude_deg, frequency_hz)));
    if (!r)
      return Result::failure(
          fmt::format("{} axis: {}", axis == TableAxis::kOuter ? "outer" : "inner", r.message));
    return r;
  }
  Result stop() override {
    // Stopping is the safe state: allowed in every lifecycle state.
    world_.table().outer().stop();
    world_.table().inner().stop();
    return Result::success();
  }
  core::TableState read_state() override { return world_.table_state(); }

 private:
  Result count(Result r) {
    if (!r) ++refused_;
    return r;
  }
  sim::SimWorld& world_;
  std::string name_ = "table";
  SimLifecycle life_;
  std::uint64_t refused_ = 0;
};

class SimStation::SimChamber final : public Chamber {
 public:
  explicit SimChamber(sim::SimWorld& world) : world_(world) {}
  const std::string& name() const override { return name_; }
  Result configure() override { return life_.configure(); }
  Result activate() override { return life_.activate(); }
  Result deactivate() override {
    world_.chamber().standby();
    return life_.deactivate();
  }
  DeviceState state() const override { return life_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override {
    return {{"refused_commands", refused_}};
  }
  Result set_temperature(double target_c, std::optional<double> ramp_c_per_min) override {
    if (auto r = life_.require_active(name_); !r) return r;
    const auto r = from_sim(world_.chamber().set_setpoint(target_c, ramp_c_per_min));
    if (!r) ++refused_;
    return r;
  }
  Result standby() override {
    world_.chamber().standby();
    return Result::success();
  }
  core::ChamberState read_state() override { return world_.chamber_state(); }

 private:
  sim::SimWorld& world_;
  std::string name_ = "chamber";
  SimLifecycle life_;
  std::uint64_t refused_ = 0;
};

class SimStation::SimImu final : public Imu {
 public:
  SimImu(sim::SimWorld& world, std::size_t index, const core::ImuConfig& config)
      : world_(world), index_(index), name_(world.imu_name(index)) {
    if (!config.serial.empty()) identity_ = UnitIdentity{config.model, config.serial, {}};
  }
  const std::string& name() const override { return name_; }
  Result configure() override { return life_.configure(); }
  Result activate() override { return life_.activate(); }
  Result deactivate() override { return life_.deactivate(); }
  DeviceState state() const override { return life_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override { return {}; }
  std::vector<core::ImuSample> poll() override {
    auto produced = world_.take_samples(index_);
    // An inactive device delivers nothing, as a closed port would.
    if (life_.state() != DeviceState::kActive) {
      in_flight_.clear();
      return {};
    }
    // A sample arrives its latency after its instant: one produced now but received later is
    // still on the way and comes with a later poll, as on a real link (a poll handing it out
    // now would give a capture starting meanwhile one sample fewer).
    in_flight_.insert(in_flight_.end(), produced.begin(), produced.end());
    const double now = world_.clock().now_s() + 1e-9;
    const auto arrived =
        std::find_if(in_flight_.begin(), in_flight_.end(),
                     [&](const core::ImuSample& s) { return s.receive_time_s > now; });
    std::vector<core::ImuSample> out(in_flight_.begin(), arrived);
    in_flight_.erase(in_flight_.begin(), arrived);
    return out;
  }
  double sample_rate_hz() const override { return world_.imu(index_).truth().sample_rate_hz; }
  std::uint64_t sequence_modulus() const override {
    return world_.imu(index_).truth().sequence_modulus;
  }
  /// A simulated unit reports the serial its station entry gives it, as a device whose
  /// protocol carries its identity would (only once configured, as over a link).
  std::optional<UnitIdentity> identity() const override {
    if (life_.state() == DeviceState::kUnconfigured) return std::nullopt;
    return identity_;
  }

 private:
  sim::SimWorld& world_;
  std::size_t index_;
  std::string name_;
  SimLifecycle life_;
  std::optional<UnitIdentity> identity_;
  std::vector<core::ImuSample> in_flight_;  ///< produced, not yet received (in order)
};

class SimStation::SimPowerSupply final : public PowerSupply {
 public:
  SimPowerSupply(sim::SimWorld& world, std::size_t imu_index, const core::PowerSupplyConfig& config)
      : world_(world),
        imu_index_(imu_index),
        config_(config),
        voltage_v_(config.voltage_v),
        current_limit_a_(config.current_limit_a) {}
  const std::string& name() const override { return config_.name; }
  const std::string& imu_name() const override { return config_.imu; }
  Result configure() override { return life_.configure(); }
  Result activate() override { return life_.activate(); }
  Result deactivate() override { return life_.deactivate(); }
  DeviceState state() const override { return life_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override {
    return {{"refused_commands", refused_}};
  }
  Result set_output(bool on) override {
    if (auto r = life_.require_active(config_.name); !r) return count(r);
    world_.set_imu_power(imu_index_, on);
    return Result::success();
  }
  Result set_voltage(double volts) override {
    if (auto r = life_.require_active(config_.name); !r) return count(r);
    if (!(volts > 0.0)) return count(Result::failure(fmt::format("voltage {} V refused", volts)));
    voltage_v_ = volts;
    return Result::success();
  }
  Result set_current_limit(double amps) override {
    if (auto r = life_.require_active(config_.name); !r) return count(r);
    if (!(amps > 0.0)) return count(Result::failure(fmt::format("current {} A refused", amps)));
    current_limit_a_ = amps;
    return Result::success();
  }
  PowerReading read() override {
    PowerReading p;
    p.ok = true;
    p.time_s = world_.now_s();
    p.output_on = world_.imu_powered(imu_index_);
    if (p.output_on) {
      p.voltage_v = voltage_v_;
      p.current_a = std::min(current_limit_a_, kLoadPowerW / voltage_v_);
    }
    return p;
  }
  Result make_safe() override {
    // Allowed in every lifecycle state: the safe state must not depend on how far bring-up got.
    if (config_.safe_state == "off") world_.set_imu_power(imu_index_, false);
    return Result::success();
  }

 private:
  /// What a simulated unit draws: about an LN200's [W].
  static constexpr double kLoadPowerW = 12.0;
  Result count(Result r) {
    if (!r) ++refused_;
    return r;
  }
  sim::SimWorld& world_;
  std::size_t imu_index_;
  core::PowerSupplyConfig config_;
  SimLifecycle life_;
  double voltage_v_;
  double current_limit_a_;
  std::uint64_t refused_ = 0;
};

SimStation::SimStation(const core::StationConfig& config, double start_time_s,
                       std::uint64_t noise_stream)
    : world_(config, start_time_s, noise_stream),
      table_(std::make_unique<SimTurntable>(world_)),
      chamber_(std::make_unique<SimChamber>(world_)) {
  for (std::size_t i = 0; i < world_.imu_count(); ++i) {
    imus_.push_back(std::make_unique<SimImu>(world_, i, config.imus.at(i)));
  }
  for (const auto& p : config.power_supplies) {
    std::size_t index = 0;
    while (index < config.imus.size() && config.imus[index].name != p.imu) ++index;
    // StationConfig::from_json has checked the name; a config built in code may not have.
    if (index == config.imus.size()) {
      throw core::InputError("power_supplies." + p.name + ".imu", "no IMU named \"" + p.imu + "\"");
    }
    supplies_.push_back(std::make_unique<SimPowerSupply>(world_, index, p));
  }
}

SimStation::~SimStation() = default;

Turntable& SimStation::table() { return *table_; }
Chamber& SimStation::chamber() { return *chamber_; }
Imu& SimStation::imu(std::size_t index) { return *imus_.at(index); }
PowerSupply& SimStation::power_supply(std::size_t index) { return *supplies_.at(index); }

}  // namespace calstand::drivers

#include "drivers/scpi_server.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "drivers/scpi_commands.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {
namespace {

/// An instrument's error queue holds this many; beyond, the last entry says it overflowed.
constexpr std::size_t kErrorQueueSize = 10;

std::string upper(std::string_view s) {
  std::string u(s);
  std::transform(u.begin(), u.end(), u.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return u;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

}  // namespace

SimScpiSupply::SimScpiSupply(sim::SimWorld& world, std::mutex& world_mutex, std::size_t imu_index,
                             double voltage_v, double current_limit_a)
    : world_(world),
      mutex_(world_mutex),
      imu_index_(imu_index),
      voltage_v_(voltage_v),
      current_limit_a_(current_limit_a) {}

void SimScpiSupply::push_error(int code, std::string_view text) {
  if (errors_.size() >= kErrorQueueSize) {
    errors_.back() = {-350, "Queue overflow"};
    return;
  }
  errors_.emplace_back(code, std::string(text));
}

std::optional<std::string> SimScpiSupply::handle(std::string_view line) {
  std::lock_guard lock(mutex_);
  line = trim(line);
  const auto space = line.find_first_of(" \t");
  const std::string header = upper(line.substr(0, space));
  const std::string_view arg =
      space == std::string_view::npos ? std::string_view() : trim(line.substr(space));
  const bool on = world_.imu_powered(imu_index_);

  const auto number = [&](double max, double& target) -> std::optional<std::string> {
    if (arg.empty()) {
      push_error(-109, "Missing parameter");
      return std::nullopt;
    }
    const auto v = scpi::parse_number(arg);
    if (!v) {
      push_error(-224, "Illegal parameter value");
    } else if (*v < 0.0 || *v > max) {
      push_error(-222, "Data out of range");
    } else {
      target = *v;
    }
    return std::nullopt;
  };

  if (header == "*IDN?") return std::string("CALSTAND,SCPI-SUPPLY-SIM,0,1.0");
  if (header == "*CLS") {
    errors_.clear();
    return std::nullopt;
  }
  if (header == "SYST:ERR?") {
    if (errors_.empty()) return std::string("0,\"No error\"");
    const auto [code, text] = errors_.front();
    errors_.pop_front();
    return fmt::format("{},\"{}\"", code, text);
  }
  if (header == "OUTP") {
    const auto state = scpi::parse_boolean(arg);
    if (!state) {
      push_error(arg.empty() ? -109 : -224,
                 arg.empty() ? "Missing parameter" : "Illegal parameter value");
    } else {
      world_.set_imu_power(imu_index_, *state);
    }
    return std::nullopt;
  }
  if (header == "OUTP?") return std::string(on ? "1" : "0");
  if (header == "VOLT") return number(kMaxVoltageV, voltage_v_);
  if (header == "CURR") return number(kMaxCurrentA, current_limit_a_);
  if (header == "VOLT?") return fmt::format("{:.4f}", voltage_v_);
  if (header == "CURR?") return fmt::format("{:.4f}", current_limit_a_);
  if (header == "MEAS:VOLT?") return fmt::format("{:.4f}", on ? voltage_v_ : 0.0);
  if (header == "MEAS:CURR?") {
    const double amps =
        on && voltage_v_ > 0.0 ? std::min(current_limit_a_, kLoadPowerW / voltage_v_) : 0.0;
    return fmt::format("{:.4f}", amps);
  }
  push_error(-113, "Undefined header");
  // A query that is not understood gets no reply either (SCPI): the client's timeout fires.
  return std::nullopt;
}

ScpiServer::ScpiServer(sim::SimWorld& world, std::mutex& world_mutex, std::size_t imu_index,
                       double voltage_v, double current_limit_a, AcutrolServerOptions options)
    : supply_(std::make_unique<SimScpiSupply>(world, world_mutex, imu_index, voltage_v,
                                              current_limit_a)) {
  SimScpiSupply* supply = supply_.get();
  server_ = std::make_unique<AcutrolServer>(
      [supply](std::string_view line, bool overlong) -> std::optional<std::string> {
        if (overlong) return std::nullopt;  // dropped whole, as an instrument's input buffer does
        return supply->handle(line);
      },
      std::move(options));
}

}  // namespace calstand::drivers

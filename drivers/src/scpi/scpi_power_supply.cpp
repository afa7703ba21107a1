#include "drivers/scpi_power_supply.hpp"

#include <fmt/format.h>

#include <exception>

#include "drivers/serial_reopen.hpp"

namespace calstand::drivers {
namespace {

using SteadyClock = std::chrono::steady_clock;
using std::chrono::milliseconds;

/// An instrument's error queue is bounded (SCPI: at least 2 entries); reading more than this
/// after one command means the replies are not error entries at all.
constexpr int kMaxErrorsRead = 20;

std::string fill(std::string_view tmpl, double value) {
  return fmt::format(fmt::runtime(tmpl), value);
}

}  // namespace

ScpiPowerSupply::ScpiPowerSupply(const core::PowerSupplyConfig& config, core::Clock& clock,
                                 const std::string& where)
    : config_(config),
      clock_(clock),
      connection_(ScpiConnection::from_json(config.connection, where)) {
  if (connection_.transport == ScpiConnection::Transport::kSerial) {
    auto port = std::make_unique<SerialPort>(connection_.serial);
    serial_ = port.get();
    transport_ = std::move(port);
  } else {
    auto client = std::make_unique<TcpClient>(connection_.tcp);
    tcp_ = client.get();
    transport_ = std::move(client);
  }
}

ScpiPowerSupply::~ScpiPowerSupply() = default;

std::map<std::string, std::uint64_t> ScpiPowerSupply::fault_counters() const {
  return counters_.snapshot();
}

// ---- link ------------------------------------------------------------------------------------

Result ScpiPowerSupply::open_link() {
  return serial_ == nullptr ? Result::success() : reopen_with_backoff(*serial_, serial_backoff_);
}

void ScpiPowerSupply::note_link_failure(const std::string& why) {
  if (link_down_) return;
  link_down_ = true;
  events_.push(clock_.now_s(), true, "power supply link lost: " + why);
}

void ScpiPowerSupply::note_link_ok() {
  if (!link_down_) return;
  link_down_ = false;
  counters_.add("reconnects");
  events_.push(clock_.now_s(), false, "power supply link back");
}

Result ScpiPowerSupply::send(const std::string& line, bool want_reply, std::string* reply) {
  const auto fail = [&](const char* counter, std::string why) {
    counters_.add(counter);
    lines_.clear();  // whatever is buffered is out of step with the commands now
    std::string message = fmt::format("'{}': {}", line, why);
    note_link_failure(message);
    // A late reply would be taken for the next query's: start the stream clean.
    if (tcp_ != nullptr) tcp_->close();
    if (serial_ != nullptr && serial_->is_open()) {
      serial_->close();
      serial_backoff_.lost(SteadyClock::now());
    }
    return Result::failure(message);
  };
  if (auto r = open_link(); !r) return fail("link_errors", r.message);
  const auto deadline = SteadyClock::now() + connection_.response_timeout;
  const auto left = [&] {
    return std::max(milliseconds(0),
                    std::chrono::duration_cast<milliseconds>(deadline - SteadyClock::now()));
  };
  // Lines nobody asked for (a reply that came after its timeout) are dropped before asking.
  lines_.clear();
  std::uint8_t buffer[512];
  if (tcp_ == nullptr || tcp_->is_connected()) {
    for (int i = 0; i < 16; ++i) {
      const IoResult r = transport_->read(buffer, milliseconds(0));
      if (!r.ok()) {
        // The supply hung up while we were idle: a lost link (event, counter) even though the
        // write below reconnects at once and this command may well succeed.
        counters_.add("link_errors");
        note_link_failure(r.error);
        break;
      }
      if (r.bytes == 0) break;
    }
  }
  std::string wire = line + "\n";
  const IoResult w =
      transport_->write(std::span<const std::uint8_t>(
                            reinterpret_cast<const std::uint8_t*>(wire.data()), wire.size()),
                        left());
  if (!w.ok()) return fail("link_errors", w.error);
  if (!want_reply) return Result::success();
  for (;;) {
    if (auto got = lines_.next()) {
      if (got->overlong) {
        counters_.add("bad_replies");
        return Result::failure(fmt::format("'{}': reply too long", line));
      }
      note_link_ok();
      *reply = got->text;
      return Result::success();
    }
    const auto wait = left();
    if (wait.count() <= 0) {
      return fail("timeouts",
                  fmt::format("no reply from the power supply ({}) within {} ms",
                              connection_.describe(), connection_.response_timeout.count()));
    }
    const IoResult r = transport_->read(buffer, wait);
    if (!r.ok()) return fail("link_errors", r.error);
    lines_.push(std::span<const std::uint8_t>(buffer, r.bytes));
  }
}

Result ScpiPowerSupply::command(const std::string& line) {
  if (auto r = send(line, false, nullptr); !r) return r;
  // Set commands are not answered: the error queue says whether the supply took it.
  std::optional<scpi::ErrorEntry> first;
  for (int i = 0; i < kMaxErrorsRead; ++i) {
    std::string reply;
    if (auto r = send(std::string(connection_.commands->error_query), true, &reply); !r) return r;
    const auto entry = scpi::parse_error_entry(reply);
    if (!entry) {
      counters_.add("bad_replies");
      return Result::failure(fmt::format("'{}': bad reply to '{}': '{}'", line,
                                         connection_.commands->error_query,
                                         acutrol::sanitize_text(reply, 60)));
    }
    if (entry->code == 0) break;
    if (!first) first = entry;
  }
  if (!first) return Result::success();
  counters_.add("refused_commands");
  const std::string why = fmt::format("power supply refused '{}': {},\"{}\"", line, first->code,
                                      acutrol::sanitize_text(first->text, 100));
  events_.push(clock_.now_s(), true, why);
  return Result::failure(why);
}

Result ScpiPowerSupply::query_number(std::string_view query, double& value) {
  std::string reply;
  if (auto r = send(std::string(query), true, &reply); !r) return r;
  const auto v = scpi::parse_number(reply);
  if (!v) {
    counters_.add("bad_replies");
    return Result::failure(
        fmt::format("'{}': not a number: '{}'", query, acutrol::sanitize_text(reply, 60)));
  }
  value = *v;
  return Result::success();
}

Result ScpiPowerSupply::query_boolean(std::string_view query, bool& value) {
  std::string reply;
  if (auto r = send(std::string(query), true, &reply); !r) return r;
  const auto v = scpi::parse_boolean(reply);
  if (!v) {
    counters_.add("bad_replies");
    return Result::failure(
        fmt::format("'{}': not ON or OFF: '{}'", query, acutrol::sanitize_text(reply, 60)));
  }
  value = *v;
  return Result::success();
}

// ---- lifecycle -------------------------------------------------------------------------------

Result ScpiPowerSupply::configure() {
  std::lock_guard lock(mutex_);
  const auto failed = [&](const std::string& why) {
    life_.set(DeviceState::kError);
    return Result::failure(
        fmt::format("{} ({}): configure: {}", config_.name, connection_.describe(), why));
  };
  if (tcp_ != nullptr) {
    if (auto error = tcp_->connect(connection_.tcp.connect_timeout); !error.empty()) {
      return failed(error);
    }
  }
  const scpi::CommandSet& c = *connection_.commands;
  std::string idn;
  if (auto r = send(std::string(c.identify), true, &idn); !r) return failed(r.message);
  events_.push(clock_.now_s(), false, "power supply: " + acutrol::sanitize_text(idn, 80));
  if (auto r = command(std::string(c.clear_status)); !r) return failed(r.message);
  if (auto r = command(fill(c.set_voltage, config_.voltage_v)); !r) return failed(r.message);
  if (auto r = command(fill(c.set_current, config_.current_limit_a)); !r) return failed(r.message);
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result ScpiPowerSupply::activate() {
  std::lock_guard lock(mutex_);
  return life_.activate();
}

Result ScpiPowerSupply::deactivate() {
  std::lock_guard lock(mutex_);
  life_.deactivate();
  return Result::success();
}

// ---- commands --------------------------------------------------------------------------------

Result ScpiPowerSupply::output_locked(bool on) {
  const scpi::CommandSet& c = *connection_.commands;
  if (auto r = command(std::string(on ? c.output_on : c.output_off)); !r) return r;
  bool state = !on;
  if (auto r = query_boolean(c.output_query, state); !r) return r;
  if (state != on) {
    return Result::failure(fmt::format("output still {} after '{}'", state ? "on" : "off",
                                       on ? c.output_on : c.output_off));
  }
  last_.output_on = on;
  return Result::success();
}

Result ScpiPowerSupply::set_output(bool on) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(config_.name); !r) return r;
  return output_locked(on);
}

Result ScpiPowerSupply::set_voltage(double volts) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(config_.name); !r) return r;
  return command(fill(connection_.commands->set_voltage, volts));
}

Result ScpiPowerSupply::set_current_limit(double amps) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(config_.name); !r) return r;
  return command(fill(connection_.commands->set_current, amps));
}

PowerReading ScpiPowerSupply::read() {
  std::lock_guard lock(mutex_);
  PowerReading p = last_;
  p.time_s = clock_.now_s();
  if (life_.state() == DeviceState::kUnconfigured) {
    p.ok = false;
    p.message = "not configured";
    return p;
  }
  const scpi::CommandSet& c = *connection_.commands;
  Result r = query_boolean(c.output_query, p.output_on);
  if (r) r = query_number(c.measure_voltage, p.voltage_v);
  if (r) r = query_number(c.measure_current, p.current_a);
  p.ok = r.ok;
  p.message = r.message;
  if (r) last_ = p;
  return p;
}

Result ScpiPowerSupply::make_safe() {
  std::lock_guard lock(mutex_);
  if (config_.safe_state != "off") return Result::success();
  // In every lifecycle state: the safe state must not depend on how far bring-up got.
  return output_locked(false);
}

std::unique_ptr<PowerSupply> make_scpi_power_supply(const core::PowerSupplyConfig& config,
                                                    core::Clock& clock, const std::string& where) {
  return std::make_unique<ScpiPowerSupply>(config, clock, where);
}

}  // namespace calstand::drivers

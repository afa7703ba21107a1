#include "drivers/modbus_chamber.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace calstand::drivers {
namespace {

using std::chrono::milliseconds;

// Reconnect backoff (wall time): quick first retry for a blip, capped so a controller that comes
// back is found within seconds.
constexpr milliseconds kFirstBackoff{200};
constexpr milliseconds kMaxBackoff{2000};

}  // namespace

struct ModbusChamber::Reading {
  double pv_c = 0.0;
  RegisterWords pv_raw;
  double sp_c = 0.0;
  std::optional<std::uint16_t> mode_raw;   // set when the map has a mode register
  std::vector<std::uint16_t> alarm_words;  // one per map.alarms, in its order
};

ModbusChamber::ModbusChamber(ModbusChamberOptions options, core::Clock& clock, std::string name)
    : options_(std::move(options)),
      clock_(clock),
      name_(std::move(name)),
      counters_({"timeouts", "bad_responses", "exceptions", "link_losses", "reconnects",
                 "out_of_range", "stale", "refused_commands", "refused_writes"}),
      link_(options_) {}

ModbusChamber::~ModbusChamber() { stop_poll_thread(); }

std::string ModbusChamber::implausible_reason(double value_c, const RegisterWords& raw) const {
  const auto& map = options_.map;
  if (raw.count == 1 && std::find(map.sensor_fault_raw.begin(), map.sensor_fault_raw.end(),
                                  raw.words[0]) != map.sensor_fault_raw.end()) {
    return fmt::format(
        "process value register {} reads {:#06x}, the controller's sensor-fault "
        "value",
        map.process_value.address, raw.words[0]);
  }
  if (!std::isfinite(value_c)) {
    return fmt::format("process value register {} is not a number (sensor fault?)",
                       map.process_value.address);
  }
  const double lo = options_.min_c - ModbusChamberOptions::kPlausibleMarginC;
  const double hi = options_.max_c + ModbusChamberOptions::kPlausibleMarginC;
  if (value_c < lo || value_c > hi) {
    return fmt::format("process value {:.1f} degC is outside the plausible range [{}, {}] degC",
                       value_c, lo, hi);
  }
  return {};
}

LinkStatus ModbusChamber::read_all(Reading& r) {
  const auto& map = options_.map;
  auto s = link_.read_field(map.process_value, r.pv_c, r.pv_raw);
  if (!s.ok()) return s;
  RegisterWords sp_raw;
  s = link_.read_field(map.setpoint, r.sp_c, sp_raw);
  if (!s.ok()) return s;
  if (map.mode) {
    std::uint16_t mode = 0;
    s = link_.read_registers(RegisterKind::kHolding, map.mode->address, {&mode, 1});
    if (!s.ok()) return s;
    r.mode_raw = mode;
  }
  r.alarm_words.assign(map.alarms.size(), 0);
  for (std::size_t i = 0; i < map.alarms.size(); ++i) {
    s = link_.read_registers(RegisterKind::kHolding, map.alarms[i].address, {&r.alarm_words[i], 1});
    if (!s.ok()) return s;
  }
  return s;
}

Result ModbusChamber::configure() {
  stop_poll_thread();
  Reading r;
  std::lock_guard link_lock(link_mutex_);
  auto s = link_.connect();
  if (s.ok()) s = read_all(r);
  std::string reason = s.ok() ? implausible_reason(r.pv_c, r.pv_raw) : s.message;
  if (!s.ok() || !reason.empty()) {
    link_.close();
    link_up_ = false;
    {
      std::lock_guard lock(state_mutex_);
      configured_ = false;
    }
    life_.set(DeviceState::kError);
    if (s.ok()) reason = link_.name() + ": " + reason;
    Result out = Result::failure(fmt::format("{} ({} map): {}", name_, options_.map.name, reason));
    // Not connected or not answering is a link problem; a controller that answered with an
    // exception or an implausible value is not.
    out.link_lost = !s.ok() && s.kind != LinkStatus::Kind::kException;
    return out;
  }
  {
    std::lock_guard lock(state_mutex_);
    configured_ = true;
    cache_ = {};
    link_error_.clear();
    command_ = Command::kNone;
    command_dirty_ = false;
    written_setpoint_c_.reset();
    reported_link_down_ = false;
    reported_bad_reading_ = false;
    was_stale_ = false;
  }
  apply_reading(r);
  consecutive_failures_ = 0;
  link_up_ = true;
  life_.set(DeviceState::kInactive);
  start_poll_thread();
  return Result::success();
}

Result ModbusChamber::activate() {
  {
    std::lock_guard lock(state_mutex_);
    if (!configured_) return Result::failure(name_ + ": not configured");
    if (!link_up_) {
      return Result::link_failure(fmt::format("{}: link down: {}", name_, link_error_));
    }
  }
  return life_.activate();
}

Result ModbusChamber::deactivate() {
  auto r = standby();
  life_.deactivate();
  return r;
}

DeviceState ModbusChamber::state() const {
  {
    std::lock_guard lock(state_mutex_);
    if (!configured_) return life_.state();
  }
  return link_up_ ? life_.state() : DeviceState::kError;
}

Result ModbusChamber::set_temperature(double target_c, std::optional<double> ramp_c_per_min) {
  if (auto r = life_.require_active(name_); !r) return r;
  auto refuse = [&](std::string why) {
    counters_.add("refused_commands");
    return Result::failure(fmt::format("{}: {}", name_, why));
  };
  if (!std::isfinite(target_c) || target_c < options_.min_c || target_c > options_.max_c) {
    return refuse(fmt::format("setpoint {} degC is outside the chamber range [{}, {}] degC",
                              target_c, options_.min_c, options_.max_c));
  }
  const double ramp = ramp_c_per_min.value_or(options_.max_ramp_c_per_min);
  if (!std::isfinite(ramp) || ramp <= 0.0 || ramp > options_.max_ramp_c_per_min) {
    return refuse(fmt::format("ramp {} degC/min is not in (0, {}] degC/min", ramp,
                              options_.max_ramp_c_per_min));
  }
  if (!encode_value(options_.map.setpoint, target_c)) {
    return refuse(fmt::format("setpoint {} degC cannot be encoded by the {} map", target_c,
                              options_.map.name));
  }
  std::lock_guard link_lock(link_mutex_);
  {
    std::lock_guard lock(state_mutex_);
    if (!link_up_) {
      return Result::link_failure(
          fmt::format("{}: link down ({}): setpoint not written", name_, link_error_));
    }
    // A ramp continues from the last step written while controlling; otherwise it starts where
    // the air is, as a controller's own ramp would.
    const bool controlling = command_ == Command::kControl && written_setpoint_c_;
    ramp_start_c_ = controlling ? *written_setpoint_c_ : cache_.air_temperature_c;
    ramp_start_s_ = clock_.now_s();
    target_c_ = target_c;
    ramp_c_per_min_ = ramp;
    command_ = Command::kControl;
    command_dirty_ = true;
    written_setpoint_c_.reset();
    refusal_reported_ = false;
  }
  return write_command_now("setpoint");
}

Result ModbusChamber::standby() {
  std::lock_guard link_lock(link_mutex_);
  {
    std::lock_guard lock(state_mutex_);
    if (!configured_) return Result::failure(name_ + ": not configured");
    // Recorded even when the link is down: the poll thread writes it on reconnect.
    command_ = Command::kStandby;
    command_dirty_ = true;
    written_setpoint_c_.reset();
    refusal_reported_ = false;
    if (!link_up_) {
      return Result::link_failure(fmt::format(
          "{}: link down ({}): standby will be written when the link is back", name_, link_error_));
    }
  }
  return write_command_now("standby");
}

Result ModbusChamber::write_command_now(const char* what) {
  // Caller holds link_mutex_. A refusal is the controller's answer (counted, reported once);
  // anything else is a link problem the poll thread recovers from.
  const auto s = drive_command();
  if (s.ok()) return Result::success();
  const bool refused = s.kind == LinkStatus::Kind::kException;
  if (refused) {
    note_refused_write(s);
  } else {
    handle_failure(s);
  }
  const auto why = fmt::format("{}: {} not written: {}", name_, what, s.message);
  return refused ? Result::failure(why) : Result::link_failure(why);
}

core::ChamberState ModbusChamber::read_state() {
  const double now = clock_.now_s();
  std::lock_guard lock(state_mutex_);
  if (!configured_) {
    core::ChamberState s;
    s.time_s = now;
    s.fault = true;
    s.fault_text = name_ + " not configured";
    return s;
  }
  auto s = cache_;
  const auto reasons = fault_reasons_locked(now);
  if (!reasons.empty()) {
    s.fault = true;
    s.fault_text = reasons;
  }
  // Not read (link down), or no valid reading for too long while nothing implausible was read:
  // the controller could not be read. An implausible reading (a sensor fault, a mode neither
  // control nor standby) is the controller's own word, not a lost link.
  const bool stale = now - last_good_s_ > options_.stale_after_s;
  s.link_lost = !link_up_ || (stale && reading_fault_.empty());
  return s;
}

std::string ModbusChamber::fault_reasons_locked(double now_s) const {
  std::string out;
  auto add = [&](const std::string& part) { out += (out.empty() ? "" : "; ") + part; };
  if (!link_up_) add("link down: " + link_error_);
  if (!reading_fault_.empty()) add(reading_fault_);
  const double age = now_s - last_good_s_;
  if (age > options_.stale_after_s) {
    add(fmt::format("no valid process value for {:.1f} s (stale after {} s)", age,
                    options_.stale_after_s));
  }
  return out;
}

LinkStatus ModbusChamber::write_standby() {
  const auto& map = options_.map;
  if (map.mode) {
    const std::uint16_t off = map.mode->standby;
    return link_.write_registers(map.mode->address, {&off, 1});
  }
  // No mode register (F4 as mapped): the only safe thing the map can do is bring the air back
  // to the lab's temperature under control, which is where standby drifts to anyway.
  return link_.write_field(map.setpoint,
                           std::clamp(options_.ambient_c, options_.min_c, options_.max_c));
}

LinkStatus ModbusChamber::drive_command() {
  const auto& map = options_.map;
  Command command;
  bool dirty;
  double target, ramp, start_c, start_s;
  std::optional<double> written;
  {
    std::lock_guard lock(state_mutex_);
    command = command_;
    dirty = command_dirty_;
    target = target_c_;
    ramp = ramp_c_per_min_;
    start_c = ramp_start_c_;
    start_s = ramp_start_s_;
    written = written_setpoint_c_;
  }
  auto done = [&](std::optional<double> setpoint) {
    std::lock_guard lock(state_mutex_);
    command_dirty_ = false;
    if (setpoint) written_setpoint_c_ = setpoint;
  };
  if (command == Command::kNone || (command == Command::kStandby && !dirty)) return {};
  if (command == Command::kStandby) {
    auto s = write_standby();
    if (s.ok()) done(std::nullopt);
    return s;
  }

  double setpoint = target;
  if (map.ramp_rate) {
    // The controller ramps by itself: rate first, so the new target is approached at it.
    if (!dirty) return {};
    if (auto s = link_.write_field(*map.ramp_rate, ramp); !s.ok()) return s;
  } else {
    // Step in station time: an accelerated (rehearsal) clock ramps proportionally faster.
    const double elapsed_min = std::max(0.0, clock_.now_s() - start_s) / 60.0;
    const double max_change = ramp * elapsed_min;
    setpoint = start_c + std::clamp(target - start_c, -max_change, max_change);
    const double step = std::max(map.setpoint.resolution(), 0.01);
    const bool due = !written || std::abs(setpoint - *written) >= step ||
                     (setpoint == target && *written != target);
    if (!due && !dirty) return {};
    if (!due) setpoint = *written;
  }
  // Setpoint before mode: switching to control first would briefly chase the old setpoint.
  if (auto s = link_.write_field(map.setpoint, setpoint); !s.ok()) return s;
  if (dirty && map.mode) {
    const std::uint16_t on = map.mode->control;
    if (auto s = link_.write_registers(map.mode->address, {&on, 1}); !s.ok()) return s;
  }
  done(setpoint);
  return {};
}

void ModbusChamber::handle_failure(const LinkStatus& status) {
  switch (status.kind) {
    case LinkStatus::Kind::kOk:
      return;
    case LinkStatus::Kind::kException:
      // The controller is there and answered: not a link problem.
      counters_.add("exceptions");
      return;
    case LinkStatus::Kind::kTimeout:
      counters_.add("timeouts");
      ++consecutive_failures_;
      break;
    case LinkStatus::Kind::kBadResponse:
      counters_.add("bad_responses");
      ++consecutive_failures_;
      break;
    case LinkStatus::Kind::kLinkDown:
      consecutive_failures_ = kMaxConsecutiveFailures;
      break;
  }
  if (consecutive_failures_ < kMaxConsecutiveFailures || !link_up_) return;
  link_.close();
  counters_.add("link_losses");
  std::lock_guard lock(state_mutex_);
  link_error_ = status.message;
  link_lost_s_ = clock_.now_s();
  link_up_ = false;
}

void ModbusChamber::note_refused_write(const LinkStatus& status) {
  counters_.add("refused_writes");
  std::lock_guard lock(state_mutex_);
  if (refusal_reported_) return;
  refusal_reported_ = true;
  events_.push(clock_.now_s(), true, "controller refused a write: " + status.message);
}

void ModbusChamber::poll_once() {
  Reading r;
  const auto s = read_all(r);
  if (!s.ok()) {
    handle_failure(s);
    return;
  }
  consecutive_failures_ = 0;
  apply_reading(r);
}

void ModbusChamber::apply_reading(const Reading& r) {
  const double now = clock_.now_s();
  const auto reason = implausible_reason(r.pv_c, r.pv_raw);
  if (!reason.empty()) counters_.add("out_of_range");
  std::lock_guard lock(state_mutex_);
  reading_fault_ = reason;
  if (reason.empty()) {
    cache_.time_s = now;
    cache_.air_temperature_c = r.pv_c;
    last_good_s_ = now;
  }
  if (std::isfinite(r.sp_c)) cache_.setpoint_c = r.sp_c;
  if (const auto& mode = options_.map.mode) {
    if (*r.mode_raw == mode->control) {
      cache_.mode = core::ChamberMode::kActive;
    } else if (*r.mode_raw == mode->standby) {
      cache_.mode = core::ChamberMode::kStandby;
    } else {
      // E.g. an F4T in manual (open-loop power): the air is not under control, whatever the
      // setpoint says.
      cache_.mode = core::ChamberMode::kFault;
      reading_fault_ += fmt::format(
          "{}controller mode register {} reads {}, neither control ({}) "
          "nor standby ({})",
          reading_fault_.empty() ? "" : "; ", mode->address, *r.mode_raw, mode->control,
          mode->standby);
    }
  } else {
    // Without a mode register the controller always controls; standby is our ambient setpoint.
    cache_.mode =
        command_ == Command::kStandby ? core::ChamberMode::kStandby : core::ChamberMode::kActive;
  }
  // The controller's own alarms: a fault with its words (which bit is which alarm is in its
  // manual), recorded as an event when it appears like any implausible reading.
  for (std::size_t i = 0; i < r.alarm_words.size() && i < options_.map.alarms.size(); ++i) {
    if (r.alarm_words[i] == 0) continue;
    const auto& alarm = options_.map.alarms[i];
    reading_fault_ += fmt::format("{}controller alarm: {} (register {}) reads {:#06x}",
                                  reading_fault_.empty() ? "" : "; ", alarm.name, alarm.address,
                                  r.alarm_words[i]);
  }
}

bool ModbusChamber::try_reconnect() {
  std::lock_guard link_lock(link_mutex_);
  Reading r;
  auto s = link_.connect();
  if (s.ok()) s = read_all(r);
  if (!s.ok()) {
    link_.close();
    std::lock_guard lock(state_mutex_);
    link_error_ = s.message;
    return false;
  }
  consecutive_failures_ = 0;
  counters_.add("reconnects");
  {
    std::lock_guard lock(state_mutex_);
    // Whatever we last commanded is written again: the controller may have been power-cycled
    // or changed at its front panel while we could not see it.
    if (command_ != Command::kNone) command_dirty_ = true;
    written_setpoint_c_.reset();
  }
  link_up_ = true;
  poll_once();
  return true;
}

void ModbusChamber::track_fault_transitions() {
  const double now = clock_.now_s();
  std::lock_guard lock(state_mutex_);
  const bool link_down = !link_up_;
  const bool bad_reading = !reading_fault_.empty();
  const bool stale = now - last_good_s_ > options_.stale_after_s;
  const bool was_link = reported_link_down_;
  const bool was_bad = reported_bad_reading_;
  const std::string link = link_.name();
  if (link_down && !was_link) {
    events_.push(now, true, fmt::format("link lost: {}; reconnecting", link_error_));
  } else if (!link_down && was_link) {
    events_.push(now, false, fmt::format("{}: link back after {:.1f} s", link, now - link_lost_s_));
  }
  if (bad_reading && !was_bad) events_.push(now, true, reading_fault_);
  if (!bad_reading && was_bad) events_.push(now, false, "readings plausible again");
  if (stale && !was_stale_) {
    counters_.add("stale");
    events_.push(now, true,
                 fmt::format("no valid process value for {} s: stale", options_.stale_after_s));
  }
  if (!stale && was_stale_) events_.push(now, false, "readings fresh again");
  was_stale_ = stale;
  reported_link_down_ = link_down;
  reported_bad_reading_ = bad_reading;
}

void ModbusChamber::start_poll_thread() {
  {
    std::lock_guard lock(wake_mutex_);
    stopping_ = false;
  }
  poll_thread_ = std::thread([this] { poll_loop(); });
}

void ModbusChamber::stop_poll_thread() {
  {
    std::lock_guard lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (poll_thread_.joinable()) poll_thread_.join();
}

void ModbusChamber::poll_loop() {
  using Wall = std::chrono::steady_clock;
  auto backoff = kFirstBackoff;
  auto next_attempt = Wall::now();
  const milliseconds period{options_.poll_period_ms};
  for (;;) {
    if (!link_up_ && Wall::now() >= next_attempt) {
      if (try_reconnect()) {
        backoff = kFirstBackoff;
      } else {
        next_attempt = Wall::now() + backoff;
        backoff = std::min(backoff * 2, kMaxBackoff);
      }
    } else if (link_up_) {
      std::lock_guard link_lock(link_mutex_);
      poll_once();
      if (link_up_) {
        const auto s = drive_command();
        if (s.kind == LinkStatus::Kind::kException) {
          note_refused_write(s);
        } else {
          handle_failure(s);
        }
      }
      if (!link_up_) next_attempt = Wall::now() + kFirstBackoff;
    }
    track_fault_transitions();
    std::unique_lock lock(wake_mutex_);
    if (wake_.wait_for(lock, period, [this] { return stopping_; })) return;
  }
}

std::unique_ptr<Chamber> make_modbus_chamber(const core::ChamberConfig& config,
                                             core::Clock& clock) {
  return std::make_unique<ModbusChamber>(ModbusChamberOptions::from_config(config), clock);
}

}  // namespace calstand::drivers

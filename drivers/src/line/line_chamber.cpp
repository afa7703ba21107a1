// A chamber driven through a command set (line_chamber.hpp).
#include "drivers/line_chamber.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace calstand::drivers::line {
namespace {

constexpr const char* kWho = "chamber controller";

// The controller's alarm words from a read_alarms (or read_air) outcome; "" when no alarm.
std::string chamber_alarm_words(const Outcome& o, bool& active) {
  const auto truth = o.truth("alarm");
  const auto count = o.maybe_number("alarm_count");
  active = truth ? *truth : (count && *count > 0.0);
  if (!active) return {};
  std::string text = o.text("alarm_text").value_or("");
  // ESPEC lists its codes after the count (",3,15"): keep the codes, not the separators.
  const auto first = text.find_first_not_of(", \t");
  text = first == std::string::npos ? std::string() : text.substr(first);
  std::string details;
  if (count && *count > 0.0) details = fmt::format("{:g} active", *count);
  if (!text.empty()) details += (details.empty() ? "" : ", ") + text;
  return details.empty() ? "controller alarm" : "controller alarm: " + details;
}

}  // namespace

LineChamber::LineChamber(const core::ChamberConfig& config, core::Clock& clock, CommandSet set,
                         std::chrono::milliseconds min_poll_interval)
    : config_(config), clock_(clock), min_poll_interval_(min_poll_interval) {
  const auto connection = LineConnection::from_json(config.connection, set, "chamber.connection");
  session_ =
      std::make_unique<LineSession>(std::move(set), connection, kWho, clock_, counters_, events_);
}

LineChamber::LineChamber(const core::ChamberConfig& config, core::Clock& clock, CommandSet set,
                         std::unique_ptr<ByteTransport> transport, std::string link_name,
                         std::chrono::milliseconds timeout,
                         std::chrono::milliseconds min_poll_interval)
    : config_(config), clock_(clock), min_poll_interval_(min_poll_interval) {
  session_ =
      std::make_unique<LineSession>(std::move(set), std::move(transport), std::move(link_name),
                                    timeout, kWho, clock_, counters_, events_);
}

LineChamber::~LineChamber() = default;

double LineChamber::setpoint_resolution_c() const {
  const auto& extras = session_->command_set().extras;
  const auto it = extras.find("setpoint_resolution_c");
  if (it != extras.end() && it->is_number() && it->get<double>() > 0.0) return it->get<double>();
  return 0.1;
}

Result LineChamber::configure() {
  std::lock_guard lock(mutex_);
  configured_ = false;
  have_reading_ = false;
  last_poll_.reset();
  last_ = {};
  read_setpoint_c_.reset();
  mode_text_.reset();
  link_lost_ = false;
  link_error_.clear();
  read_fault_.clear();
  alarm_ = false;
  alarm_words_.clear();
  ramp_fault_.clear();
  command_ = Command::kNone;
  written_setpoint_c_.reset();
  standby_pending_ = false;
  const auto& set = session_->command_set();
  auto fail = [&](const std::string& why) {
    life_.set(DeviceState::kError);
    return Result::failure(
        fmt::format("{} ({} command set, {}): {}", name_, set.name, session_->link_name(), why));
  };
  if (auto o = session_->open(); !o.ok()) return fail(o.message);
  if (session_->has("identify")) {
    const auto o = session_->run("identify");
    if (!o.ok()) return fail(o.message);
    events_.push(clock_.now_s(), false,
                 fmt::format("{} identified: {} ({} command set)", kWho,
                             o.text("identity").value_or("(no identity in the reply)"), set.name));
  }
  if (!poll()) {
    return fail(link_lost_ ? link_error_ : read_fault_);
  }
  configured_ = true;
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result LineChamber::activate() {
  {
    std::lock_guard lock(mutex_);
    if (!configured_) return Result::failure(name_ + ": not configured");
    if (link_lost_) return Result::failure(fmt::format("{}: link down: {}", name_, link_error_));
  }
  return life_.activate();
}

Result LineChamber::deactivate() {
  auto r = standby();
  life_.deactivate();
  return r;
}

DeviceState LineChamber::state() const {
  if (configured_ && link_lost_) return DeviceState::kError;
  return life_.state();
}

Outcome LineChamber::run(const char* operation, const Arguments& args) {
  return session_->run(operation, args);
}

void LineChamber::note_read_failure(const Outcome& o) {
  if (o.kind == Outcome::Kind::kRefused) {
    // The controller answered, in its own words: a fault of the chamber, not of the link.
    read_fault_ = o.message;
    return;
  }
  // No reply, a broken link or a reply out of step (the session reopens the link): the
  // controller could not be read, and the values are the last known.
  link_lost_ = true;
  link_error_ = o.message;
}

void LineChamber::note_alarm(bool active, const std::string& words) {
  if (active && !alarm_) {
    counters_.add("alarms");
    events_.push(clock_.now_s(), true, words);
  } else if (active && words != alarm_words_) {
    events_.push(clock_.now_s(), true, words);
  } else if (!active && alarm_) {
    events_.push(clock_.now_s(), false, "controller alarm cleared");
  }
  alarm_ = active;
  alarm_words_ = active ? words : std::string();
}

bool LineChamber::poll() {
  last_poll_ = std::chrono::steady_clock::now();
  const auto air = run("read_air");
  if (!air.ok()) {
    note_read_failure(air);
    return false;
  }
  const auto air_c = air.maybe_number("air_c");
  if (!air_c || !std::isfinite(*air_c)) {
    Outcome bad;
    bad.kind = Outcome::Kind::kBadReply;
    bad.message =
        fmt::format("the {} command set's read_air gave no air_c", session_->command_set().name);
    note_read_failure(bad);
    return false;
  }
  std::optional<double> setpoint = air.maybe_number("setpoint_c");
  std::optional<std::string> mode = air.text("mode");
  bool alarm = false;
  std::string alarm_words = chamber_alarm_words(air, alarm);
  if (!setpoint && session_->has("read_setpoint")) {
    const auto o = run("read_setpoint");
    if (!o.ok()) {
      note_read_failure(o);
      return false;
    }
    setpoint = o.maybe_number("setpoint_c");
  }
  if (session_->has("read_mode")) {
    const auto o = run("read_mode");
    if (!o.ok()) {
      note_read_failure(o);
      return false;
    }
    if (auto m = o.text("mode")) mode = m;
  }
  if (session_->has("read_alarms")) {
    const auto o = run("read_alarms");
    if (!o.ok()) {
      note_read_failure(o);
      return false;
    }
    alarm_words = chamber_alarm_words(o, alarm);
  }
  link_lost_ = false;
  link_error_.clear();
  read_fault_.clear();
  have_reading_ = true;
  last_.time_s = clock_.now_s();
  last_.air_temperature_c = *air_c;
  if (setpoint) read_setpoint_c_ = setpoint;
  if (mode) mode_text_ = mode;
  note_alarm(alarm, alarm_words);
  if (standby_pending_) {
    // The safe state asked for while the controller could not be reached: now.
    const auto o = run("standby");
    if (o.ok()) {
      standby_pending_ = false;
      events_.push(clock_.now_s(), false, "standby written now that the link is back");
    } else if (o.kind == Outcome::Kind::kRefused) {
      standby_pending_ = false;
      read_fault_ = "standby refused: " + o.message;
    } else {
      note_read_failure(o);
      return false;
    }
  }
  if (command_ == Command::kControl && driver_ramps()) step_ramp();
  return true;
}

void LineChamber::step_ramp() {
  const double res = setpoint_resolution_c();
  const double delta = target_c_ - ramp_start_c_;
  const double elapsed_min = std::max(0.0, clock_.now_s() - ramp_start_s_) / 60.0;
  const double max_change = ramp_c_per_min_ * elapsed_min;
  double setpoint = target_c_;
  if (std::abs(delta) > max_change) {
    // Whole steps of the controller's resolution, rounded toward the start: a step never goes
    // further than the ramp allows.
    const double change = std::copysign(std::floor(max_change / res + 1e-9) * res, delta);
    setpoint = ramp_start_c_ + change;
  }
  if (written_setpoint_c_ && std::abs(setpoint - *written_setpoint_c_) < res / 2) return;
  Arguments args;
  args.numbers["setpoint_c"] = setpoint;
  const auto o = run("set_setpoint", args);
  if (o.ok()) {
    written_setpoint_c_ = setpoint;
    ramp_fault_.clear();
    return;
  }
  if (o.kind == Outcome::Kind::kRefused) {
    if (ramp_fault_.empty()) events_.push(clock_.now_s(), true, "ramp step refused: " + o.message);
    ramp_fault_ = "ramp step refused: " + o.message;
    return;
  }
  // Not written: the next poll after the link is back writes the step due then.
  link_lost_ = true;
  link_error_ = o.message;
}

Result LineChamber::command_failure(const char* what, const Outcome& o) {
  if (o.link_lost()) {
    link_lost_ = true;
    link_error_ = o.message;
    return Result::failure(fmt::format("{}: {} not done: link down: {}", name_, what, o.message));
  }
  if (o.kind == Outcome::Kind::kRefused) {
    return Result::failure(fmt::format("{}: {} refused: {}", name_, what, o.message));
  }
  return Result::failure(fmt::format("{}: {} failed: {}", name_, what, o.message));
}

Result LineChamber::set_temperature(double target_c, std::optional<double> ramp_c_per_min) {
  if (auto r = life_.require_active(name_); !r) return r;
  if (!std::isfinite(target_c) || target_c < config_.min_c || target_c > config_.max_c) {
    counters_.add("limit_refusals");
    return Result::failure(
        fmt::format("{}: setpoint {} degC is outside the station's chamber range [{}, {}] degC",
                    name_, target_c, config_.min_c, config_.max_c));
  }
  const double ramp = ramp_c_per_min.value_or(config_.max_ramp_c_per_min);
  if (!std::isfinite(ramp) || ramp <= 0.0 || ramp > config_.max_ramp_c_per_min) {
    counters_.add("limit_refusals");
    return Result::failure(fmt::format("{}: ramp {} degC/min is not in (0, {}] degC/min", name_,
                                       ramp, config_.max_ramp_c_per_min));
  }
  std::lock_guard lock(mutex_);
  Arguments args;
  if (!driver_ramps()) {
    args.numbers["ramp_c_per_min"] = ramp;
    args.numbers["setpoint_c"] = target_c;
    if (const auto o = run("set_ramp", args); !o.ok()) return command_failure("set_ramp", o);
    written_setpoint_c_ = target_c;
  } else {
    if (!have_reading_ && !poll()) {
      return Result::failure(fmt::format("{}: no air temperature to start the ramp from: {}", name_,
                                         link_lost_ ? link_error_ : read_fault_));
    }
    // A ramp continues from the last step written while controlling; otherwise it starts where
    // the air is, as a controller's own ramp would.
    const double res = setpoint_resolution_c();
    const bool controlling = command_ == Command::kControl && written_setpoint_c_.has_value();
    const double from = controlling ? *written_setpoint_c_ : last_.air_temperature_c;
    const double start = std::abs(target_c - from) < res ? target_c : std::round(from / res) * res;
    args.numbers["setpoint_c"] = start;
    if (const auto o = run("set_setpoint", args); !o.ok()) {
      return command_failure("set_setpoint", o);
    }
    ramp_start_c_ = start;
    ramp_start_s_ = clock_.now_s();
    written_setpoint_c_ = start;
  }
  // Setpoint before start: starting first would chase the old setpoint for a moment.
  if (session_->has("start")) {
    if (const auto o = run("start"); !o.ok()) return command_failure("start", o);
  }
  command_ = Command::kControl;
  standby_pending_ = false;
  target_c_ = target_c;
  ramp_c_per_min_ = ramp;
  ramp_fault_.clear();
  return Result::success();
}

Result LineChamber::standby() {
  std::lock_guard lock(mutex_);
  if (!configured_) return Result::failure(name_ + ": not configured");
  command_ = Command::kStandby;
  written_setpoint_c_.reset();
  ramp_fault_.clear();
  standby_pending_ = false;
  if (const auto o = run("standby"); !o.ok()) {
    // Not reached: the next poll that reaches the controller writes it (the safe state must not
    // depend on the link being up at the moment it is asked for).
    standby_pending_ = o.link_lost() || o.kind == Outcome::Kind::kBadReply;
    return command_failure("standby", o);
  }
  return Result::success();
}

core::ChamberState LineChamber::compose(double now_s) const {
  core::ChamberState s = last_;
  if (!have_reading_) s.time_s = now_s;
  if (command_ == Command::kControl) {
    s.setpoint_c = target_c_;
  } else if (read_setpoint_c_) {
    s.setpoint_c = *read_setpoint_c_;
  } else if (written_setpoint_c_) {
    s.setpoint_c = *written_setpoint_c_;
  }
  std::string faults;
  auto add = [&](const std::string& part) { faults += (faults.empty() ? "" : "; ") + part; };
  if (link_lost_) {
    s.link_lost = true;
    add("link down: " + link_error_);
  }
  if (!read_fault_.empty()) add(read_fault_);
  if (mode_text_) {
    if (*mode_text_ == "active") {
      s.mode = core::ChamberMode::kActive;
    } else if (*mode_text_ == "standby") {
      s.mode = core::ChamberMode::kStandby;
    } else {
      s.mode = core::ChamberMode::kFault;
      add(*mode_text_ == "fault" ? std::string("controller in a fault mode")
                                 : fmt::format("controller mode \"{}\"", *mode_text_));
    }
  } else {
    s.mode =
        command_ == Command::kControl ? core::ChamberMode::kActive : core::ChamberMode::kStandby;
  }
  if (alarm_) {
    s.mode = core::ChamberMode::kFault;
    add(alarm_words_);
  }
  if (!ramp_fault_.empty()) add(ramp_fault_);
  s.fault = !faults.empty();
  s.fault_text = faults;
  return s;
}

core::ChamberState LineChamber::read_state() {
  const double now = clock_.now_s();
  try {
    std::lock_guard lock(mutex_);
    if (!configured_) {
      core::ChamberState s;
      s.time_s = now;
      s.fault = true;
      s.fault_text = name_ + " not configured";
      return s;
    }
    const auto wall = std::chrono::steady_clock::now();
    if (!last_poll_ || wall - *last_poll_ >= min_poll_interval_) poll();
    return compose(now);
  } catch (const std::exception& e) {
    core::ChamberState s;
    s.time_s = now;
    s.fault = true;
    s.fault_text = fmt::format("{} state unreadable: {}", name_, e.what());
    return s;
  }
}

std::unique_ptr<Chamber> make_line_chamber(const core::ChamberConfig& config, core::Clock& clock,
                                           const CommandSet& set) {
  return std::make_unique<LineChamber>(config, clock, set);
}

}  // namespace calstand::drivers::line

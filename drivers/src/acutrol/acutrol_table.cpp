#include "drivers/acutrol_table.hpp"

#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <numbers>

#include "drivers/serial_reopen.hpp"

namespace calstand::drivers {

using acutrol::Command;
using acutrol::CommandKind;

namespace {

using SteadyClock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr std::array<int, 2> kWireAxes{acutrol::kOuterAxis, acutrol::kInnerAxis};

std::string_view axis_name(int wire_axis) {
  return wire_axis == acutrol::kInnerAxis ? "inner" : "outer";
}

int wire_axis(TableAxis axis) {
  return axis == TableAxis::kInner ? acutrol::kInnerAxis : acutrol::kOuterAxis;
}

std::size_t index_of(int wire_axis) { return wire_axis == acutrol::kInnerAxis ? 1 : 0; }

/// Wraps to [-180, 180) [deg].
double wrap_180(double deg) {
  double w = std::fmod(deg + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

core::AxisMode to_axis_mode(acutrol::WireMode mode) {
  switch (mode) {
    case acutrol::WireMode::kRest:
      return core::AxisMode::kRest;
    case acutrol::WireMode::kPosition:
      return core::AxisMode::kPosition;
    case acutrol::WireMode::kRate:
      return core::AxisMode::kRate;
    case acutrol::WireMode::kSine:
      return core::AxisMode::kSine;
    case acutrol::WireMode::kFault:
      return core::AxisMode::kFault;
  }
  return core::AxisMode::kFault;
}

std::unique_ptr<ByteTransport> make_transport(const AcutrolConnection& c) {
  if (c.transport == AcutrolConnection::Transport::kSerial) {
    return std::make_unique<SerialPort>(c.serial);
  }
  return std::make_unique<TcpClient>(c.tcp);
}

Command axis_command(CommandKind kind, int axis, double value = 0.0, double value2 = 0.0) {
  return {kind, axis, value, value2};
}

}  // namespace

AcutrolTable::AcutrolTable(const core::TableConfig& config, core::Clock& clock)
    : config_(config), clock_(clock), connection_(AcutrolConnection::from_json(config.connection)) {
  transport_ = make_transport(connection_);
  link_name_ = connection_.describe();
  if (connection_.transport == AcutrolConnection::Transport::kSerial) {
    serial_ = static_cast<SerialPort*>(transport_.get());
  } else {
    tcp_ = static_cast<TcpClient*>(transport_.get());
  }
}

AcutrolTable::AcutrolTable(const core::TableConfig& config, core::Clock& clock,
                           std::unique_ptr<ByteTransport> transport,
                           std::chrono::milliseconds response_timeout)
    : config_(config), clock_(clock), transport_(std::move(transport)) {
  connection_.response_timeout = response_timeout;
  link_name_ = "given transport";
}

AcutrolTable::~AcutrolTable() = default;

std::map<std::string, std::uint64_t> AcutrolTable::fault_counters() const {
  return counters_.snapshot();
}

// ---- link ------------------------------------------------------------------------------------

Result AcutrolTable::open_link() {
  return serial_ == nullptr ? Result::success() : reopen_with_backoff(*serial_, serial_backoff_);
}

void AcutrolTable::note_link_failure(const std::string& why) {
  if (link_down_) return;
  link_down_ = true;
  events_.push(clock_.now_s(), true, "table controller link lost: " + why);
}

void AcutrolTable::note_bad_reply(const std::string& why) {
  counters_.add("bad_replies");
  if (bad_reply_reported_) return;
  bad_reply_reported_ = true;
  events_.push(clock_.now_s(), true, "bad reply from the table controller: " + why);
}

void AcutrolTable::note_link_ok() {
  if (!link_down_) return;
  link_down_ = false;
  counters_.add("reconnects");
  events_.push(clock_.now_s(), false, "table controller link back");
}

AcutrolTable::Exchange AcutrolTable::exchange(const Command& command) {
  const std::string text = acutrol::format_command(command);
  const auto fail = [&](Exchange::Outcome outcome, std::string why) {
    lines_.clear();  // whatever is buffered is out of step with the commands now
    if (outcome == Exchange::Outcome::kTimeout) counters_.add("timeouts");
    if (outcome == Exchange::Outcome::kLinkError) counters_.add("link_errors");
    std::string message = fmt::format("'{}': {}", text, why);
    if (outcome == Exchange::Outcome::kBadReply) {
      note_bad_reply(message);
    } else {
      note_link_failure(message);
    }
    // A reply that comes late would be taken for the next command's: reopen the link so that
    // the stream starts clean (TCP: a new connection; serial: the input is flushed on open).
    if (tcp_ != nullptr) tcp_->close();
    // (Only an open port: one that failed to open keeps the backoff that failure set.)
    if (serial_ != nullptr && serial_->is_open()) {
      serial_->close();
      serial_backoff_.lost(SteadyClock::now());
    }
    return Exchange{outcome, {}, std::move(message)};
  };

  if (auto r = open_link(); !r) return fail(Exchange::Outcome::kLinkError, r.message);
  const auto deadline = SteadyClock::now() + connection_.response_timeout;
  const auto left = [&] {
    return std::max(milliseconds(0),
                    std::chrono::duration_cast<milliseconds>(deadline - SteadyClock::now()));
  };

  // Bytes nobody asked for (a late reply, line noise) would be taken for this command's reply.
  std::uint8_t buffer[512];
  std::size_t stray = lines_.buffered_bytes();
  while (auto line = lines_.next()) stray += line->text.size() + 1;
  lines_.clear();
  const bool connected = tcp_ == nullptr || tcp_->is_connected();  // a closed link has nothing
  for (int i = 0; connected && i < 16; ++i) {
    const IoResult r = transport_->read(buffer, milliseconds(0));
    if (!r.ok()) {
      // The peer hung up while we were idle: that is a lost link (event, counter) even though
      // the write below reconnects at once and this command may well succeed.
      counters_.add("link_errors");
      note_link_failure(r.error);
      break;
    }
    if (r.bytes == 0) break;
    stray += r.bytes;
  }
  if (stray > 0) counters_.add("stray_bytes", stray);

  std::string wire = text;
  wire.push_back(acutrol::kTerminator);
  const IoResult w =
      transport_->write(std::span<const std::uint8_t>(
                            reinterpret_cast<const std::uint8_t*>(wire.data()), wire.size()),
                        left());
  if (!w.ok()) return fail(Exchange::Outcome::kLinkError, w.error);

  for (;;) {
    if (auto line = lines_.next()) {
      if (line->overlong) {
        return fail(Exchange::Outcome::kBadReply,
                    fmt::format("reply longer than {} bytes", acutrol::kMaxLineBytes));
      }
      note_link_ok();
      Exchange ex{Exchange::Outcome::kReply, acutrol::parse_reply(line->text), {}};
      if (ex.reply.error) {
        counters_.add("refused_commands");
        ex.outcome = Exchange::Outcome::kRefused;
        ex.message = fmt::format("controller refused '{}': ERR {} {}", text, ex.reply.error->code,
                                 ex.reply.error->text);
      }
      return ex;
    }
    const auto wait = left();
    if (wait.count() <= 0) {
      return fail(Exchange::Outcome::kTimeout,
                  fmt::format("no reply from the table controller ({}) within {} ms", link_name_,
                              connection_.response_timeout.count()));
    }
    const IoResult r = transport_->read(buffer, wait);
    if (!r.ok()) return fail(Exchange::Outcome::kLinkError, r.error);
    lines_.push(std::span<const std::uint8_t>(buffer, r.bytes));
  }
}

Result AcutrolTable::command_ok(const Command& command) {
  const Exchange ex = exchange(command);
  if (!ex.ok()) return ex.failure();
  if (!acutrol::is_ok(ex.reply)) {
    const auto why = fmt::format("'{}': expected OK, got '{}'", acutrol::format_command(command),
                                 acutrol::sanitize_text(ex.reply.payload, 60));
    note_bad_reply(why);
    return Result::failure(why);
  }
  return Result::success();
}

// ---- lifecycle -------------------------------------------------------------------------------

Result AcutrolTable::configure() {
  std::lock_guard lock(mutex_);
  const auto failed = [&](const std::string& why, bool link_lost = false) {
    life_.set(DeviceState::kError);
    Result r = Result::failure(fmt::format("{} ({}): configure: {}", name_, link_name_, why));
    r.link_lost = link_lost;
    return r;
  };
  if (tcp_ != nullptr) {
    if (auto error = tcp_->connect(connection_.tcp.connect_timeout); !error.empty()) {
      return failed(error, true);
    }
  }
  const Exchange idn = exchange({CommandKind::kIdentify, 0, 0.0, 0.0});
  if (!idn.ok()) return failed(idn.message, idn.failure().link_lost);
  events_.push(clock_.now_s(), false,
               "table controller: " + acutrol::sanitize_text(idn.reply.payload, 80));

  for (const int axis : kWireAxes) {
    const auto& limits = axis == acutrol::kInnerAxis ? config_.inner : config_.outer;
    if (auto r = command_ok(
            axis_command(CommandKind::kLimit, axis, limits.max_rate_dps, limits.max_accel_dps2));
        !r) {
      return failed(fmt::format("{} axis limits: {}", axis_name(axis), r.message), r.link_lost);
    }
  }
  for (const int axis : kWireAxes) {
    const Exchange ex = exchange(axis_command(CommandKind::kInterlockQuery, axis));
    if (!ex.ok()) return failed(ex.message, ex.failure().link_lost);
    const auto il = acutrol::parse_interlock(ex.reply.payload);
    if (!il) {
      note_bad_reply(il.error);
      return failed(il.error);
    }
    const std::size_t i = index_of(axis);
    if (il.value->open && !interlock_open_[i]) {
      counters_.add("interlock_opens");
      events_.push(clock_.now_s(), true,
                   fmt::format("{} axis interlock open: {}", axis_name(axis), il.value->why));
    }
    interlock_open_[i] = il.value->open;
  }
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result AcutrolTable::activate() {
  std::lock_guard lock(mutex_);
  const auto s = life_.state();
  if (s == DeviceState::kUnconfigured || s == DeviceState::kError) {
    return Result::failure(fmt::format("{} is {}: configure it first", name_, to_string(s)));
  }
  for (const int axis : kWireAxes) {
    const Exchange ex = exchange(axis_command(CommandKind::kInterlockQuery, axis));
    if (!ex.ok()) return ex.failure();
    const auto il = acutrol::parse_interlock(ex.reply.payload);
    if (!il) {
      note_bad_reply(il.error);
      return Result::failure(il.error);
    }
    interlock_open_[index_of(axis)] = il.value->open;
    if (!il.value->open) continue;
    // A latched interlock stays latched until someone decides to close it: a queued run
    // starting, a resume after a crash or a manual move must not close it on their way.
    return Result::failure(fmt::format(
        "{} axis interlock latched open{}: an operator must close it first (calstand device "
        "table close-interlock, or POST /station/interlock/close on the daemon)",
        axis_name(axis), il.value->why.empty() ? "" : " (" + il.value->why + ")"));
  }
  return life_.activate();
}

InterlockClosure AcutrolTable::close_interlocks() {
  std::lock_guard lock(mutex_);
  InterlockClosure out;
  const auto s = life_.state();
  if (s == DeviceState::kUnconfigured || s == DeviceState::kError) {
    out.result = Result::failure(fmt::format("{} is {}: configure it first", name_, to_string(s)));
    return out;
  }
  for (const int axis : kWireAxes) {
    const Exchange ex = exchange(axis_command(CommandKind::kInterlockQuery, axis));
    if (!ex.ok()) {
      out.result = Result::failure(ex.message);
      return out;
    }
    const auto il = acutrol::parse_interlock(ex.reply.payload);
    if (!il) {
      note_bad_reply(il.error);
      out.result = Result::failure(il.error);
      return out;
    }
    if (!il.value->open) continue;
    if (auto r = command_ok(axis_command(CommandKind::kInterlockClose, axis)); !r) {
      out.result =
          Result::failure(fmt::format("{} axis interlock: {}", axis_name(axis), r.message));
      return out;
    }
    interlock_open_[index_of(axis)] = false;
    out.closed.push_back(fmt::format("{} axis interlock{}", axis_name(axis),
                                     il.value->why.empty() ? "" : " (" + il.value->why + ")"));
    events_.push(clock_.now_s(), false, fmt::format("{} axis interlock closed", axis_name(axis)));
  }
  return out;
}

Result AcutrolTable::deactivate() {
  const Result stopped = stop();
  life_.deactivate();
  return stopped;
}

// ---- motion ----------------------------------------------------------------------------------

Result AcutrolTable::move_to(double outer_deg, double inner_deg) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  for (const int axis : kWireAxes) {
    const double deg = axis == acutrol::kInnerAxis ? inner_deg : outer_deg;
    if (!std::isfinite(deg)) {
      return Result::failure(
          fmt::format("{} axis: angle {} deg is not finite", axis_name(axis), deg));
    }
    if (auto r = command_ok(axis_command(CommandKind::kModePosition, axis)); !r) {
      return r.in(fmt::format("{} axis", axis_name(axis)));
    }
    // The controller takes any angle; wrapped here so the wire shows the angle the axis reports.
    if (auto r = command_ok(axis_command(CommandKind::kDemandPosition, axis, wrap_180(deg))); !r) {
      return r.in(fmt::format("{} axis", axis_name(axis)));
    }
  }
  return Result::success();
}

Result AcutrolTable::set_rate(TableAxis table_axis, double rate_dps) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  const int axis = wire_axis(table_axis);
  const auto& limits = table_axis == TableAxis::kInner ? config_.inner : config_.outer;
  // Checked here as well as by the controller (which got the same limit at configure): a
  // controller that lost its limits must not be the only guard.
  if (!std::isfinite(rate_dps) || std::abs(rate_dps) > limits.max_rate_dps) {
    return Result::failure(fmt::format("{} axis: rate {} deg/s is not within the limit +-{} deg/s",
                                       axis_name(axis), rate_dps, limits.max_rate_dps));
  }
  if (auto r = command_ok(axis_command(CommandKind::kModeRate, axis)); !r) {
    return r.in(fmt::format("{} axis", axis_name(axis)));
  }
  if (auto r = command_ok(axis_command(CommandKind::kDemandRate, axis, rate_dps)); !r) {
    return r.in(fmt::format("{} axis", axis_name(axis)));
  }
  return Result::success();
}

Result AcutrolTable::start_sine(TableAxis table_axis, double amplitude_deg, double frequency_hz) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  const int axis = wire_axis(table_axis);
  const auto& limits = table_axis == TableAxis::kInner ? config_.inner : config_.outer;
  // As for a rate: checked here too, so that a controller that lost its limits is not the only
  // guard.
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  if (!(amplitude_deg > 0.0) || !(frequency_hz > 0.0) || !std::isfinite(w * w * amplitude_deg) ||
      w * amplitude_deg > limits.max_rate_dps || w * w * amplitude_deg > limits.max_accel_dps2) {
    return Result::failure(fmt::format(
        "{} axis: sine {} deg at {} Hz (peak {} deg/s, {} deg/s^2) is not within the limits "
        "{} deg/s, {} deg/s^2",
        axis_name(axis), amplitude_deg, frequency_hz, w * amplitude_deg, w * w * amplitude_deg,
        limits.max_rate_dps, limits.max_accel_dps2));
  }
  if (auto r = command_ok(axis_command(CommandKind::kModeSine, axis)); !r) {
    return r.in(fmt::format("{} axis", axis_name(axis)));
  }
  if (auto r =
          command_ok(axis_command(CommandKind::kDemandSine, axis, amplitude_deg, frequency_hz));
      !r) {
    return r.in(fmt::format("{} axis", axis_name(axis)));
  }
  return Result::success();
}

Result AcutrolTable::stop() {
  std::lock_guard lock(mutex_);
  // Both axes are tried whatever happens to the first: half a stop is still safer than none.
  std::string failures;
  bool link_lost = false;
  for (const int axis : kWireAxes) {
    if (auto r = command_ok(axis_command(CommandKind::kStop, axis)); !r) {
      failures +=
          fmt::format("{}{} axis: {}", failures.empty() ? "" : "; ", axis_name(axis), r.message);
      link_lost = link_lost || r.link_lost;
    }
  }
  if (failures.empty()) return Result::success();
  Result out = Result::failure(name_ + " stop: " + failures);
  out.link_lost = link_lost;
  return out;
}

// ---- state -----------------------------------------------------------------------------------

bool AcutrolTable::read_axis(int axis, core::AxisState& out, double& angle_time_s,
                             std::string& why) {
  const double asked_s = clock_.now_s();
  const Exchange pos = exchange(axis_command(CommandKind::kReadPosition, axis));
  angle_time_s = 0.5 * (asked_s + clock_.now_s());
  const Exchange rate = pos.ok() ? exchange(axis_command(CommandKind::kReadRate, axis)) : pos;
  const Exchange status = rate.ok() ? exchange(axis_command(CommandKind::kReadStatus, axis)) : rate;
  if (!status.ok()) {
    why = status.message;
    return false;
  }
  const auto angle = acutrol::parse_number(pos.reply.payload);
  const auto rate_dps = acutrol::parse_number(rate.reply.payload);
  const auto st = acutrol::parse_status(status.reply.payload);
  if (!angle || !rate_dps || !st) {
    why = fmt::format("bad reply from the table controller: {}", !angle      ? angle.error
                                                                 : !rate_dps ? rate_dps.error
                                                                             : st.error);
    note_bad_reply(why);
    return false;
  }
  out.angle_deg = wrap_180(*angle.value);
  out.rate_dps = *rate_dps.value;
  out.mode = to_axis_mode(st.value->mode);
  out.in_position = st.value->settled;
  out.fault = st.value->mode == acutrol::WireMode::kFault || st.value->interlock_open;
  out.fault_text.clear();
  if (st.value->interlock_open) {
    const std::string& t = st.value->fault_text;
    out.fault_text = t.rfind("interlock open", 0) == 0 ? t
                     : t.empty()                       ? "interlock open"
                                                       : "interlock open: " + t;
  } else if (out.fault) {
    out.fault_text =
        st.value->fault_text.empty() ? "controller reports a fault" : st.value->fault_text;
  }
  return true;
}

void AcutrolTable::note_axis_faults(const core::TableState& state) {
  for (const int axis : kWireAxes) {
    const std::size_t i = index_of(axis);
    const auto& a = axis == acutrol::kInnerAxis ? state.inner : state.outer;
    const bool interlock = a.fault && a.fault_text.rfind("interlock open", 0) == 0;
    if (interlock && !interlock_open_[i]) {
      counters_.add("interlock_opens");
      events_.push(state.time_s, true, fmt::format("{} axis {}", axis_name(axis), a.fault_text));
    } else if (!interlock && interlock_open_[i]) {
      events_.push(state.time_s, false, fmt::format("{} axis interlock closed", axis_name(axis)));
    }
    interlock_open_[i] = interlock;
    if (a.fault && !interlock && !axis_fault_[i]) {
      events_.push(state.time_s, true,
                   fmt::format("{} axis fault: {}", axis_name(axis), a.fault_text));
    }
    axis_fault_[i] = a.fault && !interlock;
  }
}

core::TableState AcutrolTable::read_state() {
  std::lock_guard lock(mutex_);
  core::TableState s = last_;
  s.time_s = clock_.now_s();
  std::string why = "not configured (no link opened yet)";
  // Before configure() there is no link to read: say so rather than open one behind its back.
  // Stops at the first failure, so a dead controller costs one response timeout, not six.
  double outer_at_s = s.time_s, inner_at_s = s.time_s;
  if (life_.state() != DeviceState::kUnconfigured &&
      read_axis(acutrol::kOuterAxis, s.outer, outer_at_s, why) &&
      read_axis(acutrol::kInnerAxis, s.inner, inner_at_s, why)) {
    // One time for both angles: the outer's reading, the inner's moved back to it at its rate.
    // Stamping the state before its six queries made a turning axis's angle late by up to
    // three round trips, which a rehearsal at 20x turns into degrees (gravity's mean over a
    // turn's window then moved by up to 0.05 m/s^2).
    s.time_s = outer_at_s;
    s.inner.angle_deg = wrap_180(s.inner.angle_deg - s.inner.rate_dps * (inner_at_s - outer_at_s));
    s.link_lost = false;
    last_ = s;
    bad_reply_reported_ = false;
    note_axis_faults(s);
    return s;
  }
  for (auto* a : {&s.outer, &s.inner}) {
    a->fault = true;
    a->in_position = false;
    a->fault_text = "table state unreadable: " + why;
  }
  // Unreadable is not a fault the controller reports: the engine rides it out for a while.
  s.link_lost = true;
  return s;
}

std::unique_ptr<Turntable> make_acutrol_table(const core::TableConfig& config, core::Clock& clock) {
  return std::make_unique<AcutrolTable>(config, clock);
}

}  // namespace calstand::drivers

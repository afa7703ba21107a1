#include "drivers/line_table.hpp"

#include <fmt/format.h>

#include <cmath>
#include <exception>
#include <numbers>
#include <string_view>

namespace calstand::drivers {

using line::Arguments;
using line::Outcome;

namespace {

constexpr std::array<std::size_t, 2> kLineTableAxes{0, 1};  // outer, inner
// A rate the controller does not report is the angle's slope over this much station time [s]:
// long enough that the readings' time-stamp jitter (a round trip's) is a small part of it.
constexpr double kDerivedRateWindowS = 2.0;
// A derived rate is at its demand within this fraction of it (a measured one, within the
// axis's rate_tolerance_dps): the window's jitter, not the table, limits it.
constexpr double kDerivedRateTolerance = 0.01;
// Once there, a derived rate leaves its demand only beyond this fraction of it: the controller
// holds its rate to ppm, and a stamp late by a millisecond of wall time (a busy host, a
// simulator at 20x) moves the window's slope by 1 % at 60 deg/s. Without the hysteresis the
// samples of a capture at rate took that jitter for their reference rate (a rate ladder's
// gyro chi2/dof 5 to 27 through a command set without read_rate). A stall or a runaway is
// far beyond it.
constexpr double kDerivedRateHoldTolerance = 0.1;

std::string_view line_table_axis_name(std::size_t axis) { return axis == 1 ? "inner" : "outer"; }

/// Wraps to [-180, 180) [deg].
double line_table_wrap_180(double deg) {
  double w = std::fmod(deg + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

/// The command set's mode text (read_status's `mode` map values) as an axis mode.
std::optional<core::AxisMode> line_table_mode(const std::string& text) {
  if (text == "rest") return core::AxisMode::kRest;
  if (text == "position") return core::AxisMode::kPosition;
  if (text == "rate") return core::AxisMode::kRate;
  if (text == "sine") return core::AxisMode::kSine;
  if (text == "fault") return core::AxisMode::kFault;
  return std::nullopt;
}

}  // namespace

LineTable::LineTable(const core::TableConfig& config, core::Clock& clock, line::CommandSet set)
    : config_(config), clock_(clock), set_(std::move(set)) {
  const auto connection =
      line::LineConnection::from_json(config.connection, set_, "table.connection");
  session_ = std::make_unique<line::LineSession>(set_, connection, "table controller", clock_,
                                                 counters_, events_);
}

LineTable::LineTable(const core::TableConfig& config, core::Clock& clock, line::CommandSet set,
                     std::unique_ptr<ByteTransport> transport, std::chrono::milliseconds timeout)
    : config_(config), clock_(clock), set_(std::move(set)) {
  session_ =
      std::make_unique<line::LineSession>(set_, std::move(transport), "given transport", timeout,
                                          "table controller", clock_, counters_, events_);
}

LineTable::~LineTable() = default;

std::map<std::string, std::uint64_t> LineTable::fault_counters() const {
  return counters_.snapshot();
}

// ---- operations --------------------------------------------------------------------------

Arguments LineTable::axis_args(std::size_t axis) const {
  const auto& limits = axis == 1 ? config_.inner : config_.outer;
  Arguments a;
  a.texts["axis"] = axis == 1 ? set_.inner_axis : set_.outer_axis;
  a.numbers["max_rate_dps"] = limits.max_rate_dps;
  a.numbers["max_accel_dps2"] = limits.max_accel_dps2;
  return a;
}

Outcome LineTable::run(const char* operation, const Arguments& args) {
  try {
    return session_->run(operation, args);
  } catch (const std::exception& e) {
    // A user's command set whose template names an argument calstand does not give: the
    // operation cannot be sent; say so rather than throw out of the cyclic path.
    Outcome o;
    o.kind = Outcome::Kind::kBadReply;
    o.message = fmt::format("command set \"{}\", operation {}: {}", set_.name, operation, e.what());
    return o;
  }
}

Result LineTable::run_motion(const char* operation, std::size_t axis, const Arguments& args,
                             const char* expect) {
  const Outcome o = run(operation, args);
  if (!o.ok()) {
    // A command lost to the link may be sent again once it is back (the engine does so to
    // bring an axis to rest); a refusal is the controller's answer.
    const std::string why = fmt::format("{} axis: {}", line_table_axis_name(axis), o.message);
    return o.link_lost() ? Result::link_failure(why) : Result::failure(why);
  }
  // Sets whose operation ends by asking the axis's mode (ACUTROL3000): a controller that
  // silently kept another mode (an axis off, an interlock) must not look like success. An axis
  // a fault has stopped is at rest as far as stop() is concerned.
  const auto mode = o.text("mode");
  if (mode && *mode != expect && !(*mode == "fault" && std::string_view(expect) == "rest")) {
    return Result::failure(
        fmt::format("{} axis: the controller did not take {} mode: it reports {}",
                    line_table_axis_name(axis), expect, *mode));
  }
  return Result::success();
}

std::optional<LineTable::Interlock> LineTable::read_interlock(std::size_t axis, std::string& why,
                                                              bool* link_lost) {
  const Outcome o = run("read_interlock", axis_args(axis));
  if (!o.ok()) {
    why = o.message;
    if (link_lost != nullptr) *link_lost = o.link_lost();
    return std::nullopt;
  }
  const auto open = o.truth("open");
  if (!open) {
    why = fmt::format("read_interlock of the command set \"{}\" gave no \"open\"", set_.name);
    return std::nullopt;
  }
  return Interlock{*open, o.text("why").value_or("")};
}

// ---- lifecycle -----------------------------------------------------------------------------

Result LineTable::configure() {
  std::lock_guard lock(mutex_);
  const auto failed = [&](const std::string& why) {
    life_.set(DeviceState::kError);
    return Result::failure(fmt::format("{} ({}, command set \"{}\"): configure: {}", name_,
                                       session_->link_name(), set_.name, why));
  };
  if (const Outcome o = session_->open(); !o.ok()) return failed(o.message);

  if (session_->has("identify")) {
    const Outcome id = run("identify", {});
    if (!id.ok()) return failed(id.message);
    events_.push(clock_.now_s(), false,
                 "table controller: " + id.text("identity").value_or("answered " + set_.name));
  } else {
    events_.push(clock_.now_s(), false,
                 fmt::format("table controller: the command set \"{}\" has no identify: its "
                             "identity is not checked",
                             set_.name));
  }

  if (session_->has("set_limits")) {
    for (const auto axis : kLineTableAxes) {
      if (const Outcome o = run("set_limits", axis_args(axis)); !o.ok()) {
        return failed(fmt::format("{} axis limits: {}", line_table_axis_name(axis), o.message));
      }
    }
  } else {
    events_.push(clock_.now_s(), false,
                 fmt::format("the command set \"{}\" has no set_limits: the rate and sine limits "
                             "are checked by calstand only",
                             set_.name));
  }
  // What the driver does without (docs/protocols.md, "Command sets"), said once.
  if (!session_->has("read_rate")) {
    events_.push(clock_.now_s(), false,
                 fmt::format("the command set \"{}\" has no read_rate: rates are the difference "
                             "of successive angles over their times unless the position reply "
                             "gives one",
                             set_.name));
  }
  if (!session_->has("read_status")) {
    events_.push(clock_.now_s(), false,
                 fmt::format("the command set \"{}\" has no read_status: in-position is the angle "
                             "within the position tolerance of the demand for the settle time "
                             "(rate mode: the rate within the rate tolerance)",
                             set_.name));
  }
  if (!session_->has("sine")) {
    events_.push(
        clock_.now_s(), false,
        fmt::format("the command set \"{}\" has no sine: sine motion is refused", set_.name));
  }

  if (session_->has("read_interlock")) {
    for (const auto axis : kLineTableAxes) {
      std::string why;
      const auto il = read_interlock(axis, why);
      if (!il) return failed(why);
      if (il->open && !interlock_open_[axis]) {
        counters_.add("interlock_opens");
        events_.push(
            clock_.now_s(), true,
            fmt::format("{} axis interlock open: {}", line_table_axis_name(axis), il->why));
      }
      interlock_open_[axis] = il->open;
    }
  }
  for (auto& t : track_) t = AxisTrack{};
  life_.set(DeviceState::kInactive);
  return Result::success();
}

Result LineTable::activate() {
  std::lock_guard lock(mutex_);
  const auto s = life_.state();
  if (s == DeviceState::kUnconfigured || s == DeviceState::kError) {
    return Result::failure(fmt::format("{} is {}: configure it first", name_, to_string(s)));
  }
  if (session_->has("read_interlock")) {
    for (const auto axis : kLineTableAxes) {
      std::string why;
      const auto il = read_interlock(axis, why);
      if (!il) return Result::failure(why);
      interlock_open_[axis] = il->open;
      if (!il->open) continue;
      // A latched interlock stays latched until someone decides to close it: a queued run
      // starting, a resume after a crash or a manual move must not close it on their way.
      return Result::failure(fmt::format(
          "{} axis interlock latched open{}: an operator must close it first (calstand device "
          "table close-interlock, or POST /station/interlock/close on the daemon)",
          line_table_axis_name(axis), il->why.empty() ? "" : " (" + il->why + ")"));
    }
  }
  return life_.activate();
}

InterlockClosure LineTable::close_interlocks() {
  std::lock_guard lock(mutex_);
  InterlockClosure out;
  const auto s = life_.state();
  if (s == DeviceState::kUnconfigured || s == DeviceState::kError) {
    out.result = Result::failure(fmt::format("{} is {}: configure it first", name_, to_string(s)));
    return out;
  }
  if (!session_->has("read_interlock")) return out;  // none the set can see
  for (const auto axis : kLineTableAxes) {
    std::string why;
    const auto il = read_interlock(axis, why);
    if (!il) {
      out.result = Result::failure(why);
      return out;
    }
    if (!il->open) continue;
    const auto name = line_table_axis_name(axis);
    if (!session_->has("close_interlock")) {
      out.result = Result::failure(fmt::format(
          "{} axis interlock open ({}): the command set \"{}\" has no close_interlock: close it "
          "at the controller",
          name, il->why, set_.name));
      return out;
    }
    const Outcome o = run("close_interlock", axis_args(axis));
    if (!o.ok()) {
      out.result = Result::failure(fmt::format("{} axis interlock: {}", name, o.message));
      return out;
    }
    // Closing is refused while a cause is present: some controllers say so only by staying
    // open, so the interlock is read again (or taken from the close's own reply).
    std::optional<bool> still_open = o.truth("open");
    std::string still_why = o.text("why").value_or(il->why);
    if (!still_open) {
      const auto again = read_interlock(axis, why);
      if (!again) {
        out.result = Result::failure(why);
        return out;
      }
      still_open = again->open;
      still_why = again->why;
    }
    if (*still_open) {
      out.result = Result::failure(fmt::format(
          "{} axis interlock still open after close ({}): its cause is present", name, still_why));
      return out;
    }
    interlock_open_[axis] = false;
    out.closed.push_back(
        fmt::format("{} axis interlock{}", name, il->why.empty() ? "" : " (" + il->why + ")"));
    events_.push(clock_.now_s(), false, fmt::format("{} axis interlock closed", name));
  }
  return out;
}

Result LineTable::deactivate() {
  const Result stopped = stop();
  life_.deactivate();
  return stopped;
}

// ---- motion --------------------------------------------------------------------------------

Result LineTable::move_to(double outer_deg, double inner_deg) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  if (!std::isfinite(outer_deg) || !std::isfinite(inner_deg)) {
    return Result::failure(
        fmt::format("angles {} deg, {} deg are not both finite", outer_deg, inner_deg));
  }
  for (const auto axis : kLineTableAxes) {
    // The controller's angles are reported wrapped; the demand is sent the same way.
    const double deg = line_table_wrap_180(axis == 1 ? inner_deg : outer_deg);
    Arguments a = axis_args(axis);
    a.numbers["angle_deg"] = deg;
    if (auto r = run_motion("position", axis, a, "position"); !r) return r;
    auto& t = track_[axis];
    t.commanded = core::AxisMode::kPosition;
    t.demand_deg = deg;
    t.commanded_at_s = clock_.now_s();
    t.settled_since_s.reset();
  }
  return Result::success();
}

Result LineTable::set_rate(TableAxis table_axis, double rate_dps) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  const std::size_t axis = table_axis == TableAxis::kInner ? 1 : 0;
  const auto& limits = axis == 1 ? config_.inner : config_.outer;
  // Checked here as well as by the controller: a controller without set_limits, or one that
  // lost them, must not be the only guard.
  if (!std::isfinite(rate_dps) || std::abs(rate_dps) > limits.max_rate_dps) {
    return Result::failure(fmt::format("{} axis: rate {} deg/s is not within the limit +-{} deg/s",
                                       line_table_axis_name(axis), rate_dps, limits.max_rate_dps));
  }
  Arguments a = axis_args(axis);
  a.numbers["rate_dps"] = rate_dps;
  if (auto r = run_motion("rate", axis, a, "rate"); !r) return r;
  auto& t = track_[axis];
  t.commanded = core::AxisMode::kRate;
  t.demand_rate_dps = rate_dps;
  t.commanded_at_s = clock_.now_s();
  t.settled_since_s.reset();
  return Result::success();
}

Result LineTable::start_sine(TableAxis table_axis, double amplitude_deg, double frequency_hz) {
  std::lock_guard lock(mutex_);
  if (auto r = life_.require_active(name_); !r) return r;
  const std::size_t axis = table_axis == TableAxis::kInner ? 1 : 0;
  if (!session_->has("sine")) {
    return Result::failure(fmt::format(
        "{} axis: the command set \"{}\" has no sine operation: this controller cannot run a "
        "sine through calstand",
        line_table_axis_name(axis), set_.name));
  }
  const auto& limits = axis == 1 ? config_.inner : config_.outer;
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  if (!(amplitude_deg > 0.0) || !(frequency_hz > 0.0) || !std::isfinite(w * w * amplitude_deg) ||
      w * amplitude_deg > limits.max_rate_dps || w * w * amplitude_deg > limits.max_accel_dps2) {
    return Result::failure(fmt::format(
        "{} axis: sine {} deg at {} Hz (peak {} deg/s, {} deg/s^2) is not within the limits "
        "{} deg/s, {} deg/s^2",
        line_table_axis_name(axis), amplitude_deg, frequency_hz, w * amplitude_deg,
        w * w * amplitude_deg, limits.max_rate_dps, limits.max_accel_dps2));
  }
  Arguments a = axis_args(axis);
  a.numbers["amplitude_deg"] = amplitude_deg;
  a.numbers["frequency_hz"] = frequency_hz;
  if (auto r = run_motion("sine", axis, a, "sine"); !r) return r;
  auto& t = track_[axis];
  t.commanded = core::AxisMode::kSine;
  t.commanded_at_s = clock_.now_s();
  t.settled_since_s.reset();
  return Result::success();
}

Result LineTable::stop() {
  std::lock_guard lock(mutex_);
  // Both axes are tried whatever happens to the first: half a stop is still safer than none.
  std::string failures;
  for (const auto axis : kLineTableAxes) {
    if (auto r = run_motion("stop", axis, axis_args(axis), "rest"); !r) {
      failures += fmt::format("{}{}", failures.empty() ? "" : "; ", r.message);
      continue;
    }
    auto& t = track_[axis];
    t.commanded = core::AxisMode::kRest;
    t.demand_rate_dps = 0.0;
    t.commanded_at_s = clock_.now_s();
    t.settled_since_s.reset();
  }
  if (!failures.empty()) return Result::failure(name_ + " stop: " + failures);
  return Result::success();
}

// ---- state ---------------------------------------------------------------------------------

bool LineTable::read_axis(std::size_t axis, core::AxisState& out, double& angle_time_s,
                          std::string& why, bool& link_lost) {
  const Arguments args = axis_args(axis);
  const auto failed = [&](const Outcome& o) {
    why = o.message;
    link_lost = o.link_lost();
    return false;
  };
  const double asked_s = clock_.now_s();
  const Outcome pos = run("read_position", args);
  angle_time_s = 0.5 * (asked_s + clock_.now_s());
  if (!pos.ok()) return failed(pos);
  const auto angle = pos.maybe_number("angle_deg");
  if (!angle || !std::isfinite(*angle)) {
    why = fmt::format("read_position of the command set \"{}\" gave no angle_deg", set_.name);
    return false;
  }
  auto& t = track_[axis];
  const double angle_deg = line_table_wrap_180(*angle);

  // The rate: the controller's when it gives one, else the angles' difference over time.
  std::optional<double> rate = pos.maybe_number("rate_dps");
  if (!rate && session_->has("read_rate")) {
    const Outcome r = run("read_rate", args);
    if (!r.ok()) return failed(r);
    rate = r.maybe_number("rate_dps");
    if (!rate) {
      why = fmt::format("read_rate of the command set \"{}\" gave no rate_dps", set_.name);
      return false;
    }
  }
  // The angle unwrapped, kept over a window for a rate the controller does not give.
  if (t.last_angle_deg) {
    t.unwrapped_deg += line_table_wrap_180(angle_deg - *t.last_angle_deg);
  } else {
    t.unwrapped_deg = angle_deg;
  }
  t.last_angle_deg = angle_deg;
  t.last_angle_time_s = angle_time_s;
  t.history.emplace_back(angle_time_s, t.unwrapped_deg);
  // The slope is of the motion since the last command only, over at most the window.
  while (t.history.size() > 1 &&
         (t.history.front().first < t.commanded_at_s ||
          (t.history.size() > 2 && angle_time_s - t.history[1].first >= kDerivedRateWindowS))) {
    t.history.pop_front();
  }
  const bool rate_derived = !rate.has_value();
  if (rate_derived) {
    // Over a window, not between two readings: each reading's time stamp carries the link's
    // round-trip jitter, which between readings 0.1 s apart is tens of percent of the rate.
    const auto& [t0, a0] = t.history.front();
    const double dt = angle_time_s - t0;
    rate = dt > 0.0 ? (t.unwrapped_deg - a0) / dt
                    : (t.commanded == core::AxisMode::kRate ? out.rate_dps : 0.0);
  }

  std::optional<core::AxisMode> mode;
  std::optional<bool> in_position;
  bool fault = false;
  std::string fault_text;
  if (session_->has("read_status")) {
    const Outcome st = run("read_status", args);
    if (!st.ok()) return failed(st);
    if (const auto m = st.text("mode")) {
      mode = line_table_mode(*m);
      if (!mode) {
        why = fmt::format(
            "read_status of the command set \"{}\" gave mode \"{}\" (not rest, "
            "position, rate, sine or fault)",
            set_.name, *m);
        return false;
      }
    }
    in_position = st.truth("in_position");
    fault = st.truth("fault").value_or(false) || mode == core::AxisMode::kFault;
    if (fault) {
      const auto text = st.text("fault_text").value_or("");
      fault_text = text.empty() ? "the controller reports a fault" : "controller fault: " + text;
    }
  }
  std::optional<Interlock> il;
  if (session_->has("read_interlock")) {
    il = read_interlock(axis, why, &link_lost);
    if (!il) return false;
  }

  out.angle_deg = angle_deg;
  out.rate_dps = *rate;
  out.mode = mode.value_or(t.commanded);

  // In position: the controller's word in position mode when it gives one; otherwise from
  // the demand, held for the settle time.
  const auto& limits = axis == 1 ? config_.inner : config_.outer;
  const double now_s = angle_time_s;
  bool within = true;
  switch (out.mode) {
    case core::AxisMode::kPosition:
      within =
          std::abs(line_table_wrap_180(angle_deg - t.demand_deg)) <= limits.position_tolerance_deg;
      break;
    case core::AxisMode::kRate:
      // A rate derived from angles is judged to kDerivedRateTolerance of the demand, once the
      // window holds angles from after the command only.
      within = rate_derived ? t.history.front().first >= t.commanded_at_s &&
                                  std::abs(*rate - t.demand_rate_dps) <=
                                      std::max(limits.rate_tolerance_dps,
                                               (t.settled_since_s ? kDerivedRateHoldTolerance
                                                                  : kDerivedRateTolerance) *
                                                   std::abs(t.demand_rate_dps))
                            : std::abs(*rate - t.demand_rate_dps) <= limits.rate_tolerance_dps;
      break;
    case core::AxisMode::kSine:
      within = now_s - t.commanded_at_s >= limits.settle_time_s;
      break;
    case core::AxisMode::kRest:
    case core::AxisMode::kFault:
      within = true;
      break;
  }
  if (within) {
    if (!t.settled_since_s) t.settled_since_s = now_s;
  } else {
    t.settled_since_s.reset();
  }
  // A controller holds its rate to its own specification (ppm), far better than the slope of
  // angles polled over a link: once that slope agrees with the demand, the rate is the demand.
  // Likewise an axis holding its angle (settled in position, or at rest) is not turning.
  if (rate_derived && within) {
    if (out.mode == core::AxisMode::kRate) out.rate_dps = t.demand_rate_dps;
    const bool holding = out.mode == core::AxisMode::kRest ||
                         (out.mode == core::AxisMode::kPosition && t.settled_since_s &&
                          now_s - *t.settled_since_s >= limits.settle_time_s);
    if (holding) out.rate_dps = 0.0;
  }
  const bool derived =
      out.mode == core::AxisMode::kSine
          ? within
          : t.settled_since_s && now_s - *t.settled_since_s >= limits.settle_time_s;
  out.in_position = out.mode == core::AxisMode::kPosition && in_position ? *in_position
                    : out.mode == core::AxisMode::kRest || out.mode == core::AxisMode::kFault
                        ? true
                        : derived;

  out.fault = fault;
  out.fault_text = fault_text;
  if (il && il->open) {
    out.fault = true;
    out.fault_text = il->why.empty() ? "interlock open" : "interlock open: " + il->why;
  }
  if (out.fault) out.in_position = false;
  return true;
}

void LineTable::note_axis_faults(const core::TableState& state) {
  for (const auto axis : kLineTableAxes) {
    const auto& a = axis == 1 ? state.inner : state.outer;
    const auto name = line_table_axis_name(axis);
    const bool interlock = a.fault && a.fault_text.rfind("interlock open", 0) == 0;
    if (interlock && !interlock_open_[axis]) {
      counters_.add("interlock_opens");
      events_.push(state.time_s, true, fmt::format("{} axis {}", name, a.fault_text));
    } else if (!interlock && interlock_open_[axis]) {
      events_.push(state.time_s, false, fmt::format("{} axis interlock closed", name));
    }
    interlock_open_[axis] = interlock;
    if (a.fault && !interlock && !axis_fault_[axis]) {
      events_.push(state.time_s, true, fmt::format("{} axis fault: {}", name, a.fault_text));
    }
    axis_fault_[axis] = a.fault && !interlock;
  }
}

core::TableState LineTable::read_state() {
  std::lock_guard lock(mutex_);
  core::TableState s = last_;
  s.time_s = clock_.now_s();
  s.link_lost = false;
  std::string why = "not configured (no link opened yet)";
  bool link_lost = false;
  // Before configure() there is no link to read: say so rather than open one behind its back.
  // Stops at the first failure, so a dead controller costs one timeout, not eight.
  double outer_at_s = s.time_s, inner_at_s = s.time_s;
  if (life_.state() != DeviceState::kUnconfigured &&
      read_axis(0, s.outer, outer_at_s, why, link_lost) &&
      read_axis(1, s.inner, inner_at_s, why, link_lost)) {
    // One time for both angles: the outer's reading, the inner's moved back to it at its rate.
    s.time_s = outer_at_s;
    s.inner.angle_deg =
        line_table_wrap_180(s.inner.angle_deg - s.inner.rate_dps * (inner_at_s - outer_at_s));
    last_ = s;
    note_axis_faults(s);
    return s;
  }
  s.link_lost = link_lost;
  for (auto* a : {&s.outer, &s.inner}) {
    a->fault = true;
    a->in_position = false;
    a->fault_text = "table state unreadable: " + why;
  }
  return s;
}

std::unique_ptr<Turntable> make_line_table(const core::TableConfig& config, core::Clock& clock,
                                           const line::CommandSet& set) {
  return std::make_unique<LineTable>(config, clock, set);
}

}  // namespace calstand::drivers

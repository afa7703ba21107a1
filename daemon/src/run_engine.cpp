#include "daemon/run_engine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include "drivers/sample_clock.hpp"

namespace calstand::daemon {

using procedures::Step;
using procedures::StepKind;

// Encoder readings per period of an oscillation: the bandwidth analysis fits a sine at the
// known frequency to them, which 20 points a period, spread over many periods, pin well below
// the IMU's own noise.
constexpr double kTracePerCycle = 20.0;

GapPolicy parse_gap_policy(const std::string& name) {
  if (name == "record") return GapPolicy::kRecord;
  if (name == "repeat_capture") return GapPolicy::kRepeatCapture;
  if (name == "abort") return GapPolicy::kAbort;
  throw std::invalid_argument("unknown fault policy \"" + name + "\"");
}

EngineOptions EngineOptions::from_policy(const core::FaultPolicy& policy) {
  EngineOptions o;
  o.gap_policy = parse_gap_policy(policy.on_sequence_gap);
  o.stale_policy = parse_gap_policy(policy.on_stale_stream);
  o.imu_stale_s = policy.stale_after_s;
  o.link_outage_s = policy.link_outage_s;
  o.capture_band_factor = policy.capture_band_factor;
  o.max_capture_attempts = policy.max_capture_attempts;
  return o;
}

RunEngine::RunEngine(drivers::Station& station, RunJournal& journal, procedures::Plan plan,
                     EngineOptions options, std::shared_ptr<EngineCommandQueue> commands)
    : station_(station),
      journal_(journal),
      plan_(std::move(plan)),
      options_(std::move(options)),
      commands_(commands ? std::move(commands) : std::make_shared<EngineCommandQueue>()),
      imu_health_(station.imu_count()) {
  progress_.steps = plan_.steps.size();
}

Progress RunEngine::progress() const {
  std::lock_guard lock(mutex_);
  return progress_;
}

std::string RunEngine::exit_reason() const {
  std::lock_guard lock(mutex_);
  return exit_reason_;
}

void RunEngine::pause(bool immediate, const std::string& who) {
  commands_->push({EngineCommand::Kind::kPause, immediate, std::nullopt, "", who});
}

void RunEngine::resume(const std::string& who) {
  commands_->push({EngineCommand::Kind::kResume, false, std::nullopt, "", who});
}

void RunEngine::abort(const std::string& why, const std::string& who) {
  commands_->push({EngineCommand::Kind::kAbort, false, std::nullopt, why, who});
}

void RunEngine::interrupt(const std::string& why, const std::string& who) {
  commands_->push({EngineCommand::Kind::kInterrupt, false, std::nullopt, why, who});
}

void RunEngine::skip(const std::string& why, const std::string& who,
                     std::optional<std::size_t> step) {
  commands_->push({EngineCommand::Kind::kSkip, false, step, why, who});
}

void RunEngine::take_commands() {
  for (const auto& command : commands_->take_all()) apply(command);
}

// Each request is recorded as it is applied, on the engine thread (the journal is the engine
// thread's), and leaves the flags the control loop checks at its next tick or step boundary.
void RunEngine::apply(const EngineCommand& c) {
  using Kind = EngineCommand::Kind;
  switch (c.kind) {
    case Kind::kPause:
      pause_immediate_ = c.immediate;
      pause_requested_ = true;
      record_event(
          EventKind::kOperator, c.who,
          c.immediate ? "pause requested (at once)" : "pause requested (at step boundary)");
      break;
    case Kind::kResume:
      resume_requested_ = true;
      record_event(EventKind::kOperator, c.who, "resume requested");
      break;
    case Kind::kAbort:
      abort_reason_ = fmt::format("aborted by {}: {}", c.who, c.why);
      interrupt_requested_ = false;  // an operator's abort ends the run, checkpoint or not
      abort_requested_ = true;
      record_event(EventKind::kOperator, c.who, "abort requested: " + c.why);
      break;
    case Kind::kInterrupt:
      if (abort_requested_) return;  // already ending: an operator's abort stays an abort
      abort_reason_ = fmt::format("interrupted by {}: {}", c.who, c.why);
      interrupt_requested_ = true;
      abort_requested_ = true;
      record_event(EventKind::kOperator, c.who, "interrupt requested (checkpoint): " + c.why);
      break;
    case Kind::kSkip:
      skip_reason_ = fmt::format("skipped by {}: {}", c.who, c.why);
      skip_step_ = c.step;
      skip_requested_ = true;
      record_event(EventKind::kOperator, c.who,
                   c.step ? fmt::format("skip of step {} requested: {}", *c.step, c.why)
                          : "skip requested: " + c.why);
      break;
  }
}

bool RunEngine::skip_wanted() {
  if (!skip_requested_ || reestablishing_) return false;
  const std::optional<std::size_t> meant = skip_step_;
  std::size_t current = 0;
  {
    std::lock_guard lock(mutex_);
    current = progress_.step;
  }
  if (meant && *meant != current) {
    // The step the operator meant ended before the request arrived: skipping the next one
    // instead would skip what nobody asked to skip.
    skip_requested_ = false;
    record_event(
        EventKind::kInfo, "engine",
        fmt::format("skip of step {} not applied: the run is at step {}", *meant, current));
    return false;
  }
  return true;
}

void RunEngine::skip_step(std::size_t index) {
  skip_requested_ = false;
  const std::string why = skip_reason_;
  const Step& step = plan_.steps[index];
  if (step.kind == StepKind::kOscillate) station_.table().stop();  // the sine must not run on
  if (step.kind == StepKind::kRate && step.rest_after) {
    // The next step expects the table at rest, as after a completed rate step.
    const auto axis =
        step.axis == "outer" ? drivers::TableAxis::kOuter : drivers::TableAxis::kInner;
    bring_to_rest(axis, index);
  }
  journal_.step_skipped(index, station_.clock().now_s(), why);
}

void RunEngine::record_event(EventKind kind, const std::string& source,
                             const std::string& message) {
  journal_.event(station_.clock().now_s(), kind, source, message);
}

void RunEngine::set_phase(const char* phase) {
  Progress snapshot;
  {
    std::lock_guard lock(mutex_);
    progress_.phase = phase;
    progress_.state = state_.load();
    snapshot = progress_;
  }
  if (options_.on_progress) options_.on_progress(snapshot);
}

RunState RunEngine::run(std::size_t first_step, int first_attempt,
                        const std::vector<std::size_t>& skipped) {
  state_ = RunState::kRunning;
  attempt_ = first_attempt;
  journal_.run_state(RunState::kRunning, station_.clock().now_s(), "");
  try {
    if (auto r = station_.bring_up(); !r) throw StepFailed{"station bring-up: " + r.message};
    identify_units();
    // Stream health counts from now: a resumed run's clock does not start at 0.
    for (auto& h : imu_health_) h.last_sample_s = station_.clock().now_s();
    if (first_step > 0 && first_step < plan_.steps.size()) {
      {
        // Progress names the step the run resumes at while the station is made ready for it.
        std::lock_guard lock(mutex_);
        progress_.step = first_step;
        progress_.label = plan_.steps[first_step].label;
        step_started_s_ = std::numeric_limits<double>::quiet_NaN();
      }
      reestablishing_ = true;
      reestablish(first_step, skipped);
      reestablishing_ = false;
    }
    std::size_t i = first_step;
    while (i < plan_.steps.size()) {
      {
        // While paused before step i, the progress names step i (the one a skip would skip).
        std::lock_guard lock(mutex_);
        progress_.step = i;
        progress_.label = plan_.steps[i].label;
        step_started_s_ = std::numeric_limits<double>::quiet_NaN();  // not started yet
      }
      try {
        handle_pause_at_boundary();
        execute(i);
        attempt_ = 1;
        ++i;
      } catch (const Interrupted&) {
        // Paused mid-step: the next pass waits for resume, then redoes the step from its start
        // with a new attempt number (the interrupted attempt's samples were discarded).
        ++attempt_;
      } catch (const Skipped&) {
        skip_step(i);
        attempt_ = 1;
        ++i;
      }
    }
    finish(RunState::kCompleted, "");
  } catch (const Aborted& a) {
    // A checkpoint ends the run resumable; a fault during it (an interlock) still aborts it.
    // A run the operator had paused stays in the operator's hands after the restart: held.
    const bool checkpoint = interrupt_requested_ && a.why == abort_reason_;
    const bool paused = state_ == RunState::kPaused;
    finish(!checkpoint ? RunState::kAborted
           : paused    ? RunState::kHeld
                       : RunState::kInterrupted,
           a.why);
  } catch (const StepFailed& f) {
    finish(RunState::kFailed, f.why);
  } catch (...) {
    // Storage or programming error: the station is made safe before the error propagates.
    station_.make_safe();
    state_ = RunState::kFailed;
    throw;
  }
  return state_.load();
}

void RunEngine::finish(RunState final_state, const std::string& reason) {
  if (final_state != RunState::kCompleted) {
    state_ = RunState::kAborting;
    set_phase("making safe");
  }
  auto safe = station_.make_safe();
  if (!safe) {
    record_event(EventKind::kFault, "engine", "making the station safe: " + safe.message);
    // A device whose link is down (a Modbus gateway rebooting) cannot take its safe command
    // now; leaving would leave it as it was (a chamber still at +85 degC). Keep trying while
    // the drivers reconnect, then say plainly if it did not work.
    const auto give_up = std::chrono::steady_clock::now() +
                         std::chrono::duration<double>(options_.safe_state_retry_s);
    while (!safe && !station_.clock().is_virtual() && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      safe = station_.make_safe();
    }
    record_event(safe ? EventKind::kInfo : EventKind::kFault, "engine",
                 safe ? std::string("station safe") : "station NOT safe: " + safe.message);
  }
  record_device_events();
  std::string final_reason = reason;
  if (!safe)
    final_reason += (final_reason.empty() ? "" : "; ") + ("station NOT safe: " + safe.message);
  {
    std::lock_guard lock(mutex_);
    exit_reason_ = final_reason;
  }
  state_ = final_state;
  journal_.run_state(final_state, station_.clock().now_s(), final_reason);
  set_phase(to_string(final_state).data());
}

void RunEngine::handle_pause_at_boundary() {
  take_commands();
  if (!pause_requested_) return;
  pause_requested_ = false;
  // Still paused after skipping a step while paused: nothing to record again.
  if (state_ != RunState::kPaused) {
    resume_requested_ = false;
    state_ = RunState::kPaused;
    journal_.run_state(RunState::kPaused, station_.clock().now_s(), "paused");
  }
  set_phase("paused");
  for (;;) {
    take_commands();
    if (resume_requested_) break;
    if (abort_requested_) throw Aborted{abort_reason_};
    if (skip_wanted()) {
      // Skips the step that would run next; the run stays paused before the one after it.
      pause_requested_ = true;
      throw Skipped{};
    }
    // Time passes while paused (the chamber keeps holding); on a virtual clock the loop would
    // otherwise run as fast as the CPU allows, so it also sleeps a little real time.
    station_.wait_until(station_.clock().now_s() + options_.tick_s);
    poll_imus();
    set_phase("paused");  // the progress callback sees the pause (and may ask to resume)
    if (station_.clock().is_virtual()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(options_.paused_real_sleep_s));
    }
  }
  resume_requested_ = false;
  state_ = RunState::kRunning;
  journal_.run_state(RunState::kRunning, station_.clock().now_s(), "resumed");
}

void RunEngine::execute(std::size_t index) {
  const Step& step = plan_.steps[index];
  {
    std::lock_guard lock(mutex_);
    progress_.step = index;
    progress_.label = step.label;
  }
  step_started_s_ = station_.clock().now_s();
  journal_.step_started(index, attempt_, step_started_s_);
  switch (step.kind) {
    case StepKind::kSetTemperature:
      set_temperature(step, index);
      break;
    case StepKind::kMove:
      move(step, index);
      break;
    case StepKind::kRate:
      rate(step, index);
      return;  // rate() commits its own capture attempt
    case StepKind::kOscillate:
      oscillate(step, index);
      return;  // as rate()
    case StepKind::kCapture:
      attempt_ = capture(index, step.duration_s, attempt_);
      return;
    case StepKind::kWait:
      wait_for(step.duration_s, "waiting");
      break;
    case StepKind::kPower:
      power(step, index);
      break;
  }
  journal_.step_completed(index, attempt_, station_.clock().now_s());
}

void RunEngine::set_temperature(const Step& step, std::size_t index) {
  if (auto r = station_.chamber().set_temperature(step.target_c, step.ramp_c_per_min); !r) {
    throw StepFailed{fmt::format("step {} ({}): chamber refused {} degC: {}", index, step.label,
                                 step.target_c, r.message)};
  }
  if (!step.wait_for_soak) {
    // A ramp the following captures record: no band to hold them to.
    setpoint_c_.reset();
    return;
  }
  setpoint_c_ = step.target_c;
  soak_ = step.soak;
  band_c_ = options_.capture_band_factor * step.soak.tolerance_c;
  soak(step, index);
}

void RunEngine::soak(const Step& step, std::size_t index) {
  set_phase("soaking");
  const double start = station_.clock().now_s();
  double stable_since = -1.0;
  for (;;) {
    tick();
    const double now = station_.clock().now_s();
    const double air = station_.chamber().read_state().air_temperature_c;
    if (std::abs(air - step.target_c) <= step.soak.tolerance_c) {
      if (stable_since < 0.0) stable_since = now;
      if (now - stable_since >= step.soak.stable_s) return;
    } else {
      stable_since = -1.0;
    }
    if (now - start > step.soak.timeout_s) {
      throw StepFailed{fmt::format(
          "step {} ({}): soak timeout after {:.0f} s: air {:.2f} degC, target {:.2f} +/- {:.2f}",
          index, step.label, step.soak.timeout_s, air, step.target_c, step.soak.tolerance_c)};
    }
  }
}

void RunEngine::move(const Step& step, std::size_t index) {
  if (auto r = station_.table().move_to(step.outer_deg, step.inner_deg); !r) {
    throw StepFailed{
        fmt::format("step {} ({}): table refused the move: {}", index, step.label, r.message)};
  }
  set_phase("moving");
  const double start = station_.clock().now_s();
  for (;;) {
    tick();
    const auto s = station_.table().read_state();
    if (s.outer.in_position && s.inner.in_position) return;
    if (station_.clock().now_s() - start > options_.move_timeout_s) {
      throw StepFailed{fmt::format("step {} ({}): table did not settle within {:.0f} s", index,
                                   step.label, options_.move_timeout_s)};
    }
  }
}

void RunEngine::rate(const Step& step, std::size_t index) {
  const auto axis = step.axis == "outer" ? drivers::TableAxis::kOuter : drivers::TableAxis::kInner;
  if (auto r = station_.table().set_rate(axis, step.rate_dps); !r) {
    throw StepFailed{
        fmt::format("step {} ({}): table refused the rate: {}", index, step.label, r.message)};
  }
  set_phase("settling");
  const double start = station_.clock().now_s();
  for (;;) {
    tick();
    const auto s = station_.table().read_state();
    const auto& a = axis == drivers::TableAxis::kOuter ? s.outer : s.inner;
    if (a.in_position) break;
    if (station_.clock().now_s() - start > options_.rate_settle_timeout_s) {
      throw StepFailed{fmt::format(
          "step {} ({}): rate did not settle within {:.0f} s (axis at {:.6f} deg/s, mode {})",
          index, step.label, options_.rate_settle_timeout_s, a.rate_dps, core::to_string(a.mode))};
    }
  }
  wait_for(step.settle_s, "settling");
  attempt_ = capture(index, step.duration_s, attempt_);
  // The table comes to rest after a rate step unless the next step turns the same axis on.
  if (step.rest_after) bring_to_rest(axis, index);
}

void RunEngine::bring_to_rest(drivers::TableAxis axis, std::size_t index) {
  for (;;) {
    const drivers::Result r = station_.table().set_rate(axis, 0.0);
    if (r) return;
    const Step& step = plan_.steps[index];
    if (!r.link_lost) {
      throw StepFailed{fmt::format("step {} ({}): table refused to bring the axis to rest: {}",
                                   index, step.label, r.message)};
    }
    // The controller keeps the axis turning until the command reaches it: the next step must
    // not start on a turning table, so wait the outage out (or abort past the policy's limit,
    // which brings the table to its safe state once the link allows).
    ride_out_link_outage("table", true, r.message, table_link_down_since_s_);
    station_.wait_until(station_.clock().now_s() + options_.tick_s);
    poll_imus();
    record_device_events();
  }
}

void RunEngine::oscillate(const Step& step, std::size_t index) {
  const auto axis = step.axis == "outer" ? drivers::TableAxis::kOuter : drivers::TableAxis::kInner;
  const core::TableState start = station_.table().read_state();
  if (auto r = station_.table().start_sine(axis, step.amplitude_deg, step.frequency_hz); !r) {
    throw StepFailed{
        fmt::format("step {} ({}): table refused the sine: {}", index, step.label, r.message)};
  }
  // The tick (and with it the IMU polls and the encoder readings) follows the sine while it
  // runs; whatever ends the step (interrupt, abort, failure) ends the tracing with it.
  struct Tracing {
    double& tick_s;
    ~Tracing() { tick_s = 0.0; }
  } tracing{trace_tick_s_};
  trace_tick_s_ = std::min(options_.tick_s, 1.0 / (kTracePerCycle * step.frequency_hz));
  wait_for(step.settle_cycles / step.frequency_hz, "oscillating");
  attempt_ = capture(index, step.duration_s, attempt_);
  trace_tick_s_ = 0.0;
  // Back at rest where it started, so that the next step finds the table as a move left it.
  Step back = step;
  back.outer_deg = start.outer.angle_deg;
  back.inner_deg = start.inner.angle_deg;
  move(back, index);
}

int RunEngine::capture(std::size_t index, double duration_s, int first_attempt) {
  int attempt = first_attempt;
  std::string last_invalid_reason;
  for (int tries = 0; tries < options_.max_capture_attempts; ++tries, ++attempt) {
    if (tries > 0) journal_.step_started(index, attempt, station_.clock().now_s());
    // The capture is the window [start, start + duration) of sample times, not a number of
    // control ticks: ticks land wherever the clock's phase puts them (after a resume, say),
    // and a rate capture asked for whole revolutions must hold whole revolutions. Samples from
    // before the window arrive in its first poll and are left out there (not drained by a poll
    // now, which would take the sample stamped at the window's first instant with them).
    // Both edges a microsecond early: a sample that falls on an edge (the clock and the
    // sample grid in step, as on a simulated station) belongs to the window it starts, however
    // the time stamps round, so the window holds duration x rate samples, not one fewer.
    constexpr double kEdgeS = 1e-6;
    const double start = station_.clock().now_s() - kEdgeS;
    capturing_ = Capturing{index,
                           attempt,
                           std::nullopt,
                           start,
                           start + duration_s,
                           std::vector<bool>(station_.imu_count(), false)};
    set_phase("capturing");
    auto window_filled = [&] {
      const double now = station_.clock().now_s();
      if (now < capturing_->end_s) return false;
      // A silent stream whose staleness the policy only records must not hold the run.
      if (now >= capturing_->end_s + options_.imu_stale_s) return true;
      return std::all_of(capturing_->reached_end.begin(), capturing_->reached_end.end(),
                         [](bool b) { return b; });
    };
    try {
      // A link delivers late: past the window's end, wait for each stream's first sample
      // beyond it (a stream that stays silent goes stale, and its policy decides).
      while (!window_filled() && !capturing_->invalid_reason) tick();
    } catch (...) {
      // Interrupted, aborted or failed mid-capture: the partial attempt is worthless.
      journal_.discard_attempt(index, attempt, "capture interrupted");
      capturing_.reset();
      throw;
    }
    const auto invalid = capturing_->invalid_reason;
    capturing_.reset();
    if (!invalid) {
      journal_.step_completed(index, attempt, station_.clock().now_s());
      return attempt;
    }
    journal_.discard_attempt(index, attempt, *invalid);
    last_invalid_reason = *invalid;
    record_event(
        EventKind::kInterlock, "engine",
        fmt::format("step {} capture attempt {} invalidated: {}", index, attempt, *invalid));
    if (tries + 1 == options_.max_capture_attempts) break;  // no attempt left to prepare for
    // A repeat while an IMU is still silent, or its reader still catching up, would be invalid
    // at once: give the streams time to come back first.
    wait_for_streams();
    // Before repeating, command the setpoint again (the controller may have been upset) and
    // let the chamber come back into its band (re-soak).
    if (setpoint_c_) {
      Step resoak;
      resoak.label = "re-soak";
      resoak.target_c = *setpoint_c_;
      resoak.soak = soak_;
      if (auto r = station_.chamber().set_temperature(resoak.target_c, std::nullopt); !r) {
        throw StepFailed{fmt::format("step {}: re-soak: chamber refused {} degC: {}", index,
                                     resoak.target_c, r.message)};
      }
      soak(resoak, index);
    }
  }
  journal_.step_failed(index, attempt - 1, station_.clock().now_s(),
                       "capture invalidated too often");
  throw StepFailed{fmt::format("step {}: capture invalidated {} times (last: {})", index,
                               options_.max_capture_attempts, last_invalid_reason)};
}

void RunEngine::wait_for_streams() {
  const double hold_s = options_.stamps_hold_wall_s * station_.clock().time_scale();
  // Stale, or its stamps set back lately (its reader still catching up on a hold-up).
  auto any_unsettled = [&] {
    const double now = station_.clock().now_s();
    for (const auto& h : imu_health_) {
      if (h.stale || now - h.set_back_at_s < hold_s) return true;
    }
    return false;
  };
  if (!any_unsettled()) return;
  set_phase("waiting for IMU streams");
  const double end = station_.clock().now_s() + options_.stream_recovery_timeout_s;
  while (any_unsettled() && station_.clock().now_s() < end) tick();
}

void RunEngine::power(const Step& step, std::size_t index) {
  std::vector<std::size_t> units;
  for (std::size_t i = 0; i < station_.imu_count(); ++i) {
    const std::string& name = station_.imu(i).name();
    if (!step.imu.empty() && name != step.imu) continue;
    drivers::PowerSupply* supply = station_.supply_of(name);
    if (supply == nullptr) continue;  // the plan has refused a named unit without a supply
    if (auto r = supply->set_output(step.power_on); !r) {
      throw StepFailed{fmt::format("step {} ({}): {} refused power {}: {}", index, step.label,
                                   supply->name(), step.power_on ? "on" : "off", r.message)};
    }
    record_event(EventKind::kInfo, supply->name(),
                 fmt::format("{} powered {}", name, step.power_on ? "on" : "off"));
    ImuHealth& health = imu_health_[i];
    health.unpowered = !step.power_on;
    // A unit that starts again counts from 0: its first sample is no sequence gap, and its
    // clock starts again.
    health.last_sequence.reset();
    health.last_stamp_offset_s.reset();
    health.stale = false;
    health.last_sample_s = station_.clock().now_s();
    units.push_back(i);
  }
  if (step.power_on) {
    set_phase("waiting for IMU streams after power on");
    const double on_s = station_.clock().now_s();
    const auto started = [&](std::size_t i) { return imu_health_[i].last_sample_s > on_s; };
    // Each unit's own limit, from the supply that feeds it (station file power_supplies).
    const auto start_timeout_s = [&](std::size_t i) {
      for (const core::PowerSupplyConfig& p : station_.config().power_supplies) {
        if (p.imu == station_.imu(i).name()) return p.start_timeout_s;
      }
      return core::PowerSupplyConfig{}.start_timeout_s;
    };
    for (;;) {
      tick();
      const bool all = std::all_of(units.begin(), units.end(), started);
      if (all) break;
      const double waited_s = station_.clock().now_s() - on_s;
      for (std::size_t i : units) {
        if (started(i) || waited_s < start_timeout_s(i)) continue;
        throw StepFailed{
            fmt::format("{} did not start streaming within {:g} s after power on "
                        "(its supply's start_timeout_s)",
                        station_.imu(i).name(), start_timeout_s(i))};
      }
    }
  }
  wait_for(step.settle_s, step.power_on ? "settling after power on" : "settling after power off");
}

void RunEngine::wait_for(double duration_s, const char* phase) {
  set_phase(phase);
  const double end = station_.clock().now_s() + duration_s;
  while (station_.clock().now_s() < end - 1e-9) tick();
}

void RunEngine::identify_units() {
  for (std::size_t i = 0; i < station_.imu_count(); ++i) {
    drivers::Imu& imu = station_.imu(i);
    const std::optional<drivers::UnitIdentity> id = imu.identity();
    if (!id) continue;
    if (std::string why = journal_.unit_identified(imu.name(), id->model, id->serial);
        !why.empty()) {
      throw StepFailed{"unit check: " + why};
    }
    record_event(
        EventKind::kInfo, imu.name(),
        "unit " + id->serial + (id->model.empty() ? "" : " (" + id->model + ")") + " identified");
  }
}

void RunEngine::reestablish(std::size_t first_step, const std::vector<std::size_t>& skipped) {
  // Resuming after a crash: the step about to run needs the temperature and the table
  // position the steps before it left. Re-run the last temperature step (with its soak) and
  // the last move; a rate step sets its own rate.
  std::optional<std::size_t> last_temperature, last_move;
  for (std::size_t i = 0; i < first_step && i < plan_.steps.size(); ++i) {
    // A skipped step left nothing to re-establish (a soak the chamber could not reach must
    // not be commanded again after a restart).
    if (std::find(skipped.begin(), skipped.end(), i) != skipped.end()) continue;
    if (plan_.steps[i].kind == StepKind::kSetTemperature) last_temperature = i;
    if (plan_.steps[i].kind == StepKind::kMove) last_move = i;
  }
  record_event(
      EventKind::kInfo, "engine",
      fmt::format("resuming at step {}: re-establishing temperature and position", first_step));
  // The supplies as the power steps before it left them (a restarted station may have
  // switched them by its safe state): replayed in order, the last one per unit wins.
  for (std::size_t i = 0; i < first_step && i < plan_.steps.size(); ++i) {
    const Step& s = plan_.steps[i];
    if (s.kind != StepKind::kPower) continue;
    if (std::find(skipped.begin(), skipped.end(), i) != skipped.end()) continue;
    for (std::size_t u = 0; u < station_.imu_count(); ++u) {
      const std::string& name = station_.imu(u).name();
      if (!s.imu.empty() && name != s.imu) continue;
      drivers::PowerSupply* supply = station_.supply_of(name);
      if (supply == nullptr) continue;
      if (auto r = supply->set_output(s.power_on); !r) {
        throw StepFailed{fmt::format("re-establishing power of {}: {}", name, r.message)};
      }
      imu_health_[u].unpowered = !s.power_on;
      imu_health_[u].last_sequence.reset();
      imu_health_[u].last_stamp_offset_s.reset();
    }
  }
  if (last_temperature) set_temperature(plan_.steps[*last_temperature], *last_temperature);
  if (last_move) move(plan_.steps[*last_move], *last_move);
}

void RunEngine::tick() {
  take_commands();
  if (abort_requested_) throw Aborted{abort_reason_};
  if (pause_requested_ && pause_immediate_ && !reestablishing_) throw Interrupted{};
  if (skip_wanted()) throw Skipped{};
  const double now = station_.clock().now_s();
  station_.wait_until(now + (trace_tick_s_ > 0.0 ? trace_tick_s_ : options_.tick_s));
  poll_imus();
  record_device_events();
  check_interlocks();
  const double t = station_.clock().now_s();
  if (trace_tick_s_ > 0.0) journal_.table_trace(station_.table().read_state());
  if (t - last_telemetry_s_ >= options_.telemetry_period_s) {
    if (trace_tick_s_ <= 0.0) journal_.table_telemetry(station_.table().read_state());
    journal_.chamber_telemetry(station_.chamber().read_state());
    last_telemetry_s_ = t;
  }
  Progress snapshot;
  {
    std::lock_guard lock(mutex_);
    progress_.state = state_.load();
    progress_.station_time_s = t;
    // The current step's estimate less the time it has run (never below zero: a soak may
    // take longer than planned), then the steps after it.
    double remaining = 0.0;
    if (progress_.step < plan_.step_duration_s.size()) {
      const double planned = plan_.step_duration_s[progress_.step];
      remaining =
          std::isnan(step_started_s_) ? planned : std::max(0.0, planned - (t - step_started_s_));
    }
    for (std::size_t i = progress_.step + 1; i < plan_.step_duration_s.size(); ++i) {
      remaining += plan_.step_duration_s[i];
    }
    progress_.eta_s = remaining;
    snapshot = progress_;
  }
  if (options_.on_progress) options_.on_progress(snapshot);
}

void RunEngine::poll_imus() {
  const double now = station_.clock().now_s();
  for (std::size_t i = 0; i < station_.imu_count(); ++i) {
    drivers::Imu& imu = station_.imu(i);
    ImuHealth& health = imu_health_[i];
    const auto samples = imu.poll();
    if (samples.empty()) {
      if (!health.unpowered && now - health.last_sample_s > options_.imu_stale_s) {
        if (!health.stale) {
          health.stale = true;
          record_event(
              EventKind::kFault, imu.name(),
              fmt::format("stream stale: no sample for {:.1f} s", now - health.last_sample_s));
        }
        // Every capture that sees the stream silent is affected, not only the one during which
        // it fell silent: a repeated capture of a still-silent IMU must not pass as valid.
        if (capturing_ && !capturing_->invalid_reason &&
            options_.stale_policy == GapPolicy::kRepeatCapture) {
          capturing_->invalid_reason = imu.name() + " stream stale";
        } else if (capturing_ && options_.stale_policy == GapPolicy::kAbort) {
          throw Aborted{imu.name() + ": stream stale"};
        }
      }
      continue;
    }
    if (health.stale) {
      health.stale = false;
      record_event(EventKind::kInfo, imu.name(), "stream back");
    }
    health.last_sample_s = now;
    // 64-bit arithmetic: a 32-bit counter wraps at 2^32, which a uint32_t cannot hold.
    const std::uint64_t modulus = imu.sequence_modulus();
    std::uint64_t missing = 0;
    for (const auto& s : samples) {
      if (health.last_sequence) {
        const std::uint64_t expected = (std::uint64_t{*health.last_sequence} + 1) % modulus;
        if (s.sequence != expected) {
          missing += (std::uint64_t{s.sequence} + modulus - expected) % modulus;
        }
      }
      health.last_sequence = s.sequence;
    }
    if (const double late_s = stamps_set_back_s(health, samples); late_s > 0.0) {
      health.set_back_at_s = station_.clock().now_s();
      record_event(EventKind::kFault, imu.name(),
                   fmt::format("time stamps set back {:.3f} s: the stream was held up longer than "
                               "its clock estimate could tell, and its samples were stamped late",
                               late_s));
      if (capturing_ && !capturing_->invalid_reason &&
          options_.stale_policy == GapPolicy::kRepeatCapture) {
        capturing_->invalid_reason =
            fmt::format("{} samples stamped up to {:.3f} s late", imu.name(), late_s);
      } else if (capturing_ && options_.stale_policy == GapPolicy::kAbort) {
        throw Aborted{fmt::format("{}: samples stamped up to {:.3f} s late", imu.name(), late_s)};
      }
    }
    if (missing > 0) {
      record_event(EventKind::kFault, imu.name(),
                   fmt::format("sequence gap: {} samples missing", missing));
      if (capturing_) {
        if (options_.gap_policy == GapPolicy::kRepeatCapture) {
          capturing_->invalid_reason = fmt::format("{}: {} samples missing", imu.name(), missing);
        } else if (options_.gap_policy == GapPolicy::kAbort) {
          throw Aborted{fmt::format("{}: sequence gap of {} samples", imu.name(), missing)};
        }
      }
    }
    if (capturing_ && !capturing_->invalid_reason) {
      // Only the samples stamped inside the window belong to the capture. A real link
      // delivers late, so samples from before the window can arrive in its first poll; the
      // last poll brings samples from after it. Neither belongs to any step.
      std::vector<core::ImuSample> in_window;
      const std::vector<core::ImuSample>* in_capture = &samples;
      if (samples.back().receive_time_s >= capturing_->end_s) capturing_->reached_end[i] = true;
      if (samples.front().receive_time_s < capturing_->start_s ||
          samples.back().receive_time_s >= capturing_->end_s) {
        for (const auto& s : samples) {
          if (s.receive_time_s >= capturing_->start_s && s.receive_time_s < capturing_->end_s) {
            in_window.push_back(s);
          }
        }
        in_capture = &in_window;
      }
      if (in_capture->empty()) continue;
      bool queued =
          journal_.add_samples(capturing_->step, capturing_->attempt, imu.name(), *in_capture);
      if (!queued && station_.clock().is_virtual()) {
        // Simulated time waits for the disk: back-pressure, not loss.
        journal_.wait_for_writer();
        queued =
            journal_.add_samples(capturing_->step, capturing_->attempt, imu.name(), *in_capture);
      }
      if (!queued) {
        record_event(EventKind::kFault, "writer", "capture queue overflow: samples not stored");
        capturing_->invalid_reason = "capture writer overflow";
      }
    }
  }
}

double RunEngine::stamps_set_back_s(ImuHealth& health,
                                    const std::vector<core::ImuSample>& samples) const {
  // A streaming driver stamps a sample with its device time plus an offset it estimates from
  // the arrivals (drivers::SampleClock): the least delay seen lately. A stream held up for
  // longer than that memory has its hold-up taken for the link's delay, and its samples are
  // stamped late: a capture window then takes in samples from before it (the end of a move,
  // the last position) and lets later ones out, with nothing else to show for it. When the
  // stream catches up, the estimate comes back down: station minus device time falls below
  // what it was, by as much as the stamps had been late. Limits in wall seconds, as the
  // driver's: link and scheduling delays do not speed up with an accelerated station clock.
  const double k = station_.clock().time_scale();
  const double tolerance_s = options_.late_stamp_wall_s * k;
  const double memory_s = drivers::SampleClock::kWindowWallS * k;  // the estimate's memory
  const double jump_s = drivers::SampleClock::kJumpWallS * k;      // a leap restarts the estimate
  double set_back_s = 0.0;
  for (const auto& s : samples) {
    const double offset = s.receive_time_s - s.device_time_s;
    const double device_step_s = s.device_time_s - health.last_device_time_s;
    health.last_device_time_s = s.device_time_s;
    // A device clock that jumped (restart, wrap, time set) starts a new estimate: the stamps
    // before it were not late for that (the driver reports the jump itself).
    if (!health.last_stamp_offset_s || device_step_s <= 0.0 || device_step_s > jump_s ||
        s.device_time_s - health.offset_high_at_s > memory_s ||
        offset > health.stamp_offset_high_s) {
      health.stamp_offset_high_s = offset;
      health.offset_high_at_s = s.device_time_s;
      health.set_back_said_s = 0.0;
    }
    health.last_stamp_offset_s = offset;
    // Stamps held at the last one fall a sample period at a time: said once the fall passes
    // the tolerance, and again only as it grows by as much again.
    const double fallen_s = health.stamp_offset_high_s - offset;
    if (fallen_s > health.set_back_said_s + tolerance_s) {
      set_back_s = fallen_s;
      health.set_back_said_s = fallen_s;
    }
  }
  return set_back_s;
}

void RunEngine::record_device_events() {
  // What the drivers saw on their links (frame errors, lost and restored links, refused
  // writes) goes into the run's log under the device's name, at the time it was seen.
  auto drain = [&](drivers::Device& device) {
    for (const auto& e : device.take_events()) {
      journal_.event(e.time_s, e.fault ? EventKind::kFault : EventKind::kInfo, device.name(),
                     e.message);
    }
  };
  drain(station_.table());
  drain(station_.chamber());
  for (std::size_t i = 0; i < station_.imu_count(); ++i) drain(station_.imu(i));
}

bool RunEngine::ride_out_link_outage(const std::string& device, bool link_lost,
                                     const std::string& fault_text,
                                     std::optional<double>& down_since_s) {
  // The driver says whether it could not read the controller (link_lost) or the controller
  // reported a fault; only the first is ridden out.
  if (!link_lost) return false;
  const double now = station_.clock().now_s();
  if (!down_since_s) {
    down_since_s = now;
    // The controllers keep their setpoint, rate or position on their own: a short outage
    // costs readings, not the run.
    record_event(EventKind::kFault, device,
                 fmt::format("link lost ({}); riding it out for up to {:.0f} s", fault_text,
                             options_.link_outage_s));
  }
  if (now - *down_since_s > options_.link_outage_s) {
    const std::string why = fmt::format(
        "{} link down for {:.1f} s (more than the policy's {:.0f} "
        "s): {}",
        device, now - *down_since_s, options_.link_outage_s, fault_text);
    record_event(EventKind::kInterlock, device, why);
    throw Aborted{why};
  }
  return true;
}

void RunEngine::note_link_back(const std::string& device, std::optional<double>& down_since_s) {
  if (!down_since_s) return;
  record_event(EventKind::kInfo, device,
               fmt::format("link back after {:.1f} s", station_.clock().now_s() - *down_since_s));
  down_since_s.reset();
}

void RunEngine::check_interlocks() {
  const auto table = station_.table().read_state();
  if (table.outer.fault || table.inner.fault) {
    const std::string& text = table.outer.fault ? table.outer.fault_text : table.inner.fault_text;
    // A controller fault known from before the link went (a last-known axis in fault mode) is
    // not ridden out: the link coming back would not clear it.
    const bool outage = table.link_lost && table.outer.mode != core::AxisMode::kFault &&
                        table.inner.mode != core::AxisMode::kFault;
    if (!ride_out_link_outage("table", outage, text, table_link_down_since_s_)) {
      const std::string why = table.outer.fault ? "outer axis: " + table.outer.fault_text
                                                : "inner axis: " + table.inner.fault_text;
      record_event(EventKind::kInterlock, "table", "table fault: " + why);
      throw Aborted{"table fault: " + why};
    }
  } else {
    note_link_back("table", table_link_down_since_s_);
  }
  const auto chamber = station_.chamber().read_state();
  if (chamber.fault) {
    const bool outage = chamber.link_lost && chamber.mode != core::ChamberMode::kFault;
    if (!ride_out_link_outage("chamber", outage, chamber.fault_text, chamber_link_down_since_s_)) {
      record_event(EventKind::kInterlock, "chamber", "chamber fault: " + chamber.fault_text);
      throw Aborted{"chamber fault: " + chamber.fault_text};
    }
    return;  // no air temperature to hold the capture's band to while the link is down
  }
  note_link_back("chamber", chamber_link_down_since_s_);
  if (capturing_ && setpoint_c_ && !capturing_->invalid_reason &&
      std::abs(chamber.air_temperature_c - *setpoint_c_) > band_c_) {
    capturing_->invalid_reason =
        fmt::format("chamber air {:.2f} degC left the band {:.2f} +/- {:.2f} degC",
                    chamber.air_temperature_c, *setpoint_c_, band_c_);
  }
}

}  // namespace calstand::daemon

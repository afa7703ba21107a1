#include "daemon/run_engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <thread>

#include "drivers/sim_station.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"

namespace calstand::daemon {
namespace {

using procedures::Step;
using procedures::StepKind;

// Records what the engine tells it, in memory.
class MemoryJournal final : public RunJournal {
 public:
  struct Attempt {
    std::size_t samples = 0;
    double first_time_s = 0.0;
    double last_time_s = 0.0;
  };
  void step_started(std::size_t step, int attempt, double) override {
    started.push_back({step, attempt});
  }
  bool add_samples(std::size_t step, int attempt, const std::string& device,
                   const std::vector<core::ImuSample>& s) override {
    Attempt& a = attempts[{step, attempt, device}];
    if (a.samples == 0) a.first_time_s = s.front().receive_time_s;
    a.samples += s.size();
    a.last_time_s = s.back().receive_time_s;
    if (refuse_samples_until_wait && waits == 0) return false;
    return !refuse_samples;
  }
  void wait_for_writer() override { ++waits; }
  void discard_attempt(std::size_t step, int attempt, const std::string& why) override {
    discarded.push_back({step, attempt});
    discard_reasons.push_back(why);
    std::erase_if(attempts, [&](const auto& e) {
      return std::get<0>(e.first) == step && std::get<1>(e.first) == attempt;
    });
  }
  void step_completed(std::size_t step, int attempt, double) override {
    completed.push_back({step, attempt});
  }
  void step_failed(std::size_t step, int, double, const std::string& why) override {
    failed.push_back({step, why});
  }
  void step_skipped(std::size_t step, double, const std::string& why) override {
    skipped.push_back({step, why});
  }
  void event(double, EventKind kind, const std::string& source,
             const std::string& message) override {
    events.push_back({kind, source + ": " + message});
  }
  void table_telemetry(const core::TableState&) override { ++table_rows; }
  void chamber_telemetry(const core::ChamberState&) override { ++chamber_rows; }
  void run_state(RunState state, double, const std::string&) override { states.push_back(state); }
  std::string unit_identified(const std::string& imu, const std::string&,
                              const std::string& serial) override {
    units[imu] = serial;
    return {};
  }

  bool has_event(EventKind kind, const std::string& text) const {
    for (const auto& [k, m] : events) {
      if (k == kind && m.find(text) != std::string::npos) return true;
    }
    return false;
  }

  std::vector<std::pair<std::size_t, int>> started, completed, discarded;
  std::vector<std::string> discard_reasons;
  std::vector<std::pair<std::size_t, std::string>> failed, skipped;
  std::map<std::tuple<std::size_t, int, std::string>, Attempt> attempts;
  std::vector<std::pair<EventKind, std::string>> events;
  std::vector<RunState> states;
  std::map<std::string, std::string> units;  ///< serial reported per IMU slot
  int table_rows = 0, chamber_rows = 0;
  bool refuse_samples = false;
  bool refuse_samples_until_wait = false;
  int waits = 0;
};

Step temperature(double c) {
  Step s;
  s.kind = StepKind::kSetTemperature;
  s.label = "to " + std::to_string(c);
  s.target_c = c;
  s.wait_for_soak = true;
  s.soak = {0.5, 120.0, 7200.0};
  return s;
}
Step move(double outer, double inner) {
  Step s;
  s.kind = StepKind::kMove;
  s.label = "move";
  s.outer_deg = outer;
  s.inner_deg = inner;
  return s;
}
Step capture(double seconds) {
  Step s;
  s.kind = StepKind::kCapture;
  s.label = "capture";
  s.duration_s = seconds;
  return s;
}
Step rate(const char* axis, double dps, double seconds) {
  Step s;
  s.kind = StepKind::kRate;
  s.label = "rate";
  s.axis = axis;
  s.rate_dps = dps;
  s.settle_s = 1.0;
  s.duration_s = seconds;
  s.rest_after = true;
  return s;
}

procedures::Plan plan_of(std::vector<Step> steps) {
  procedures::Plan p;
  for (std::size_t i = 0; i < steps.size(); ++i) steps[i].index = i;
  p.steps = std::move(steps);
  p.step_duration_s.assign(p.steps.size(), 10.0);
  return p;
}

struct Fixture {
  drivers::SimStation station{sim::default_station()};
  MemoryJournal journal;
};

std::size_t samples_of(const MemoryJournal& j, std::size_t step) {
  std::size_t n = 0;
  for (const auto& [key, a] : j.attempts) {
    if (std::get<0>(key) == step) n += a.samples;
  }
  return n;
}

TEST(RunEngine, RunsEveryStepAndEndsSafe) {
  Fixture f;
  RunEngine engine(f.station, f.journal,
                   plan_of({temperature(30.0), move(180.0, 0.0), capture(5.0),
                            rate("inner", 90.0, 4.0), capture(2.0)}));
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.completed.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(f.journal.completed[i].first, i);
  // 400 Hz IMU: a 5 s capture holds 2000 samples (the window's edges: one sample).
  EXPECT_NEAR(static_cast<double>(samples_of(f.journal, 2)), 2000.0, 1.0);
  EXPECT_NEAR(static_cast<double>(samples_of(f.journal, 3)), 1600.0, 1.0);
  EXPECT_EQ(samples_of(f.journal, 0), 0u);  // only recording steps keep samples
  EXPECT_EQ(f.journal.states.front(), RunState::kRunning);
  EXPECT_EQ(f.journal.states.back(), RunState::kCompleted);
  EXPECT_GT(f.journal.chamber_rows, 10);
  // Safe at the end: table at rest, chamber in standby.
  const auto table = f.station.table().read_state();
  EXPECT_NEAR(table.inner.rate_dps, 0.0, 1e-6);
  EXPECT_EQ(f.station.chamber().read_state().mode, core::ChamberMode::kStandby);
  // Capture at outer 180: the IMU is upside down.
  EXPECT_EQ(engine.progress().state, RunState::kCompleted);
}

// A resumed run's clock starts wherever the crash left it, so the control ticks fall at any
// phase of the IMU's sample grid. Two revolutions at 10 deg/s are 72 s: 28,800 samples at
// 400 Hz covering 720 deg, to within one sample, at every phase.
TEST(RunEngine, WholeRevolutionCaptureHoldsWholeRevolutionsWhateverTheClockPhase) {
  for (const double start_s : {0.0, 0.0371, 1234567.0613, 86400.00013, 3.3e6 + 0.0999}) {
    drivers::SimStation station{sim::default_station(), start_s};
    MemoryJournal journal;
    RunEngine engine(station, journal, plan_of({rate("inner", 10.0, 72.0), capture(4.0)}));
    ASSERT_EQ(engine.run(), RunState::kCompleted) << "start " << start_s;
    EXPECT_NEAR(static_cast<double>(samples_of(journal, 0)), 28800.0, 1.0) << "start " << start_s;
    EXPECT_NEAR(static_cast<double>(samples_of(journal, 1)), 1600.0, 1.0) << "start " << start_s;
    for (const auto& [key, a] : journal.attempts) {
      if (std::get<0>(key) != 0) continue;
      // First to last sample spans the window less one sample period: 720 deg, to within one
      // sample (0.025 deg; a little more for the rounding of the time stamps).
      const double covered_deg = 10.0 * (a.last_time_s - a.first_time_s + 1.0 / 400.0);
      EXPECT_NEAR(covered_deg, 720.0, 1.001 * 10.0 / 400.0) << "start " << start_s;
    }
  }
}

TEST(RunEngine, PauseAtBoundaryThenResume) {
  Fixture f;
  RunEngine* e = nullptr;
  bool paused_once = false;
  EngineOptions opt;
  opt.paused_real_sleep_s = 0.0;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && !paused_once) {
      paused_once = true;
      e->pause(false);
    }
    if (p.state == RunState::kPaused) e->resume();
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(1.0), capture(1.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_TRUE(std::find(f.journal.states.begin(), f.journal.states.end(), RunState::kPaused) !=
              f.journal.states.end());
  EXPECT_TRUE(f.journal.discarded.empty());  // a boundary pause interrupts nothing
  EXPECT_EQ(f.journal.completed.size(), 3u);
  EXPECT_TRUE(f.journal.has_event(EventKind::kOperator, "pause requested"));
}

TEST(RunEngine, ImmediatePauseDiscardsAndRepeatsTheCapture) {
  Fixture f;
  RunEngine* e = nullptr;
  bool paused_once = false;
  EngineOptions opt;
  opt.paused_real_sleep_s = 0.0;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing" && p.station_time_s > 2.5 && !paused_once) {
      paused_once = true;
      e->pause(true);
    }
    if (p.state == RunState::kPaused) e->resume();
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(3.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.discarded.size(), 1u);
  EXPECT_EQ(f.journal.discarded[0], std::make_pair(std::size_t{1}, 1));
  EXPECT_EQ(f.journal.completed.back(), std::make_pair(std::size_t{1}, 2));
  // The repeated capture is whole: 3 s at 400 Hz.
  EXPECT_NEAR(static_cast<double>(samples_of(f.journal, 1)), 1200.0, 1.0);
}

TEST(RunEngine, AbortTakesTheStationSafeAndRecordsWhy) {
  Fixture f;
  RunEngine* e = nullptr;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 2 && p.phase == "capturing") e->abort("operator saw smoke", "alice");
  };
  RunEngine engine(
      f.station, f.journal,
      plan_of({temperature(40.0), rate("inner", 100.0, 30.0), capture(60.0), capture(1.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kAborted);
  EXPECT_NE(engine.exit_reason().find("operator saw smoke"), std::string::npos);
  EXPECT_NE(engine.exit_reason().find("alice"), std::string::npos);
  EXPECT_EQ(f.journal.completed.size(), 2u);
  EXPECT_EQ(f.journal.discarded.size(), 1u);  // the cut capture
  EXPECT_EQ(f.station.chamber().read_state().mode, core::ChamberMode::kStandby);
  EXPECT_EQ(f.journal.states.back(), RunState::kAborted);
}

TEST(RunEngine, ChamberLeavingItsBandInvalidatesTheCaptureWhichIsRepeatedAfterResoak) {
  Fixture f;
  bool upset = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing" && !upset) {
      upset = true;  // a controller upset: the air heads 5 degC away
      f.station.world().chamber().set_setpoint(35.0);
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({temperature(30.0), capture(300.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.discarded.size(), 1u);
  EXPECT_NE(f.journal.discard_reasons[0].find("left the band"), std::string::npos);
  EXPECT_TRUE(f.journal.has_event(EventKind::kInterlock, "invalidated"));
  EXPECT_EQ(f.journal.completed.back(), std::make_pair(std::size_t{1}, 2));
  EXPECT_NEAR(static_cast<double>(samples_of(f.journal, 1)), 120000.0, 100.0);
}

TEST(RunEngine, TableFaultAbortsToSafeState) {
  Fixture f;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 0 && p.phase == "capturing") {
      f.station.world().table().outer().inject_fault("amplifier trip");
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({rate("inner", 50.0, 20.0), capture(1.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kAborted);
  EXPECT_NE(engine.exit_reason().find("amplifier trip"), std::string::npos);
  EXPECT_TRUE(f.journal.has_event(EventKind::kInterlock, "table fault"));
  f.station.world().advance(10.0);
  EXPECT_NEAR(f.station.table().read_state().inner.rate_dps, 0.0, 1e-6);
}

/// The simulated chamber behind a link that is down between station times [lost_from_s,
/// lost_until_s): meanwhile its state is the last known with a link fault, as the Modbus driver
/// reports it. `flagged` false gives the same fault text without link_lost; `fault_mode` makes
/// the last known state a controller fault.
class ChamberBehindALink final : public drivers::Chamber {
 public:
  ChamberBehindALink(drivers::Chamber& inner, core::Clock& clock) : inner_(inner), clock_(clock) {}
  double lost_from_s = 1e300;
  double lost_until_s = 1e300;
  bool flagged = true;
  bool fault_mode = false;

  const std::string& name() const override { return inner_.name(); }
  drivers::Result configure() override { return inner_.configure(); }
  drivers::Result activate() override { return inner_.activate(); }
  drivers::Result deactivate() override { return inner_.deactivate(); }
  drivers::DeviceState state() const override { return inner_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override { return {}; }
  drivers::Result set_temperature(double c, std::optional<double> ramp) override {
    return inner_.set_temperature(c, ramp);
  }
  drivers::Result standby() override { return inner_.standby(); }
  core::ChamberState read_state() override {
    const double now = clock_.now_s();
    if (now < lost_from_s || now >= lost_until_s) return last_ = inner_.read_state();
    core::ChamberState s = last_;
    s.fault = true;
    s.fault_text = "link down: scripted outage";
    s.link_lost = flagged;
    if (fault_mode) s.mode = core::ChamberMode::kFault;
    return s;
  }

 private:
  drivers::Chamber& inner_;
  core::Clock& clock_;
  core::ChamberState last_;
};

/// The simulated station with its chamber behind ChamberBehindALink.
class StationWithALink final : public drivers::Station {
 public:
  StationWithALink() : chamber_(sim_.chamber(), sim_.clock()) {}
  ChamberBehindALink& link() { return chamber_; }
  const core::StationConfig& config() const override { return sim_.config(); }
  core::Clock& clock() override { return sim_.clock(); }
  drivers::Turntable& table() override { return sim_.table(); }
  drivers::Chamber& chamber() override { return chamber_; }
  std::size_t imu_count() const override { return sim_.imu_count(); }
  drivers::Imu& imu(std::size_t i) override { return sim_.imu(i); }
  void wait_until(double t_s) override { sim_.wait_until(t_s); }

 private:
  drivers::SimStation sim_{sim::default_station()};
  ChamberBehindALink chamber_;
};

TEST(RunEngine, AChamberLinkLostForLessThanThePolicyIsRiddenOut) {
  StationWithALink station;
  station.link().lost_from_s = 2.0;
  station.link().lost_until_s = 4.0;
  MemoryJournal journal;
  EngineOptions opt;
  opt.link_outage_s = 5.0;
  RunEngine engine(station, journal, plan_of({capture(8.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kCompleted) << engine.exit_reason();
  EXPECT_TRUE(journal.has_event(EventKind::kFault, "link lost (link down: scripted outage)"));
  EXPECT_TRUE(journal.has_event(EventKind::kInfo, "chamber: link back after"));
}

TEST(RunEngine, AChamberLinkLostForLongerThanThePolicyAbortsNamingIt) {
  StationWithALink station;
  station.link().lost_from_s = 2.0;
  MemoryJournal journal;
  EngineOptions opt;
  opt.link_outage_s = 3.0;
  RunEngine engine(station, journal, plan_of({capture(20.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kAborted);
  const std::string why = engine.exit_reason();
  EXPECT_NE(why.find("chamber link down for "), std::string::npos) << why;
  EXPECT_NE(why.find("(more than the policy's 3 s): link down: scripted outage"), std::string::npos)
      << why;
}

// The flag, not the wording: a fault that reads like a lost link but is not flagged as one, or
// a lost link whose last known state was a controller fault, aborts at once.
TEST(RunEngine, OnlyAFlaggedLinkLossOfAControllerNotInFaultIsRiddenOut) {
  for (const bool text_only : {true, false}) {
    StationWithALink station;
    station.link().lost_from_s = 2.0;
    station.link().lost_until_s = 2.5;
    station.link().flagged = !text_only;
    station.link().fault_mode = !text_only;
    MemoryJournal journal;
    RunEngine engine(station, journal, plan_of({capture(8.0)}));
    EXPECT_EQ(engine.run(), RunState::kAborted) << (text_only ? "text only" : "in fault");
    EXPECT_NE(engine.exit_reason().find("chamber fault: link down: scripted outage"),
              std::string::npos)
        << engine.exit_reason();
  }
}

/// The simulated table behind a link that goes down at the first command to bring an axis to
/// rest and stays down for `outage_s` of station time: the command is lost (link_failure) and
/// the state is the last known with link_lost, as the ACUTROL and command-set drivers give.
class TableBehindALink final : public drivers::Turntable {
 public:
  TableBehindALink(drivers::Turntable& inner, core::Clock& clock) : inner_(inner), clock_(clock) {}
  double outage_s = 0.0;
  int rest_commands_lost = 0;

  const std::string& name() const override { return inner_.name(); }
  drivers::Result configure() override { return inner_.configure(); }
  drivers::Result activate() override { return inner_.activate(); }
  drivers::Result deactivate() override { return inner_.deactivate(); }
  drivers::DeviceState state() const override { return inner_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override { return {}; }
  drivers::Result move_to(double outer, double inner) override {
    if (down()) return drivers::Result::link_failure("no reply: scripted outage");
    return inner_.move_to(outer, inner);
  }
  drivers::Result set_rate(drivers::TableAxis axis, double rate_dps) override {
    if (rate_dps == 0.0 && !lost_at_s_) lost_at_s_ = clock_.now_s();
    if (down()) {
      ++rest_commands_lost;
      return drivers::Result::link_failure("no reply: scripted outage");
    }
    return inner_.set_rate(axis, rate_dps);
  }
  drivers::Result start_sine(drivers::TableAxis axis, double amplitude, double f) override {
    return inner_.start_sine(axis, amplitude, f);
  }
  drivers::Result stop() override { return down() ? drivers::Result::success() : inner_.stop(); }
  core::TableState read_state() override {
    if (!down()) return last_ = inner_.read_state();
    core::TableState s = last_;
    s.outer.fault = true;
    s.outer.fault_text = "link down: scripted outage";
    s.link_lost = true;
    return s;
  }

 private:
  bool down() const {
    return lost_at_s_ && clock_.now_s() >= *lost_at_s_ && clock_.now_s() < *lost_at_s_ + outage_s;
  }
  drivers::Turntable& inner_;
  core::Clock& clock_;
  std::optional<double> lost_at_s_;
  core::TableState last_;
};

/// The simulated station with its table behind TableBehindALink.
class StationWithATableLink final : public drivers::Station {
 public:
  StationWithATableLink() : table_(sim_.table(), sim_.clock()) {}
  TableBehindALink& link() { return table_; }
  drivers::SimStation& sim() { return sim_; }
  const core::StationConfig& config() const override { return sim_.config(); }
  core::Clock& clock() override { return sim_.clock(); }
  drivers::Turntable& table() override { return table_; }
  drivers::Chamber& chamber() override { return sim_.chamber(); }
  std::size_t imu_count() const override { return sim_.imu_count(); }
  drivers::Imu& imu(std::size_t i) override { return sim_.imu(i); }
  void wait_until(double t_s) override { sim_.wait_until(t_s); }

 private:
  drivers::SimStation sim_{sim::default_station()};
  TableBehindALink table_;
};

// A link outage that swallows the command bringing a rate step's axis to rest: the engine sends
// it again once the link is back, so the next step's capture is on a table at rest (it used to
// start on a table still turning at the step's rate).
TEST(RunEngine, ARestCommandLostToALinkOutageIsSentAgainBeforeTheNextStep) {
  StationWithATableLink station;
  station.link().outage_s = 2.0;
  MemoryJournal journal;
  EngineOptions opt;
  opt.link_outage_s = 5.0;
  // The inner axis's rate at the end of the next step's capture (braking takes 0.1 s).
  std::optional<double> inner_rate_in_next_capture;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing") {
      inner_rate_in_next_capture = station.sim().table().read_state().inner.rate_dps;
    }
  };
  RunEngine engine(station, journal, plan_of({rate("inner", 50.0, 3.0), capture(2.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kCompleted) << engine.exit_reason();
  EXPECT_GE(station.link().rest_commands_lost, 1);
  ASSERT_TRUE(inner_rate_in_next_capture.has_value());
  EXPECT_NEAR(*inner_rate_in_next_capture, 0.0, 1e-6);
  EXPECT_TRUE(journal.has_event(EventKind::kFault, "link lost (no reply: scripted outage)"));
}

TEST(RunEngine, ARestCommandLostForLongerThanThePolicyAbortsNamingTheTableLink) {
  StationWithATableLink station;
  station.link().outage_s = 60.0;
  MemoryJournal journal;
  EngineOptions opt;
  opt.link_outage_s = 3.0;
  RunEngine engine(station, journal, plan_of({rate("inner", 50.0, 3.0), capture(2.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kAborted);
  EXPECT_NE(engine.exit_reason().find("table link down for "), std::string::npos)
      << engine.exit_reason();
}

TEST(RunEngine, SequenceGapIsRecordedOrRepeatsTheCaptureByPolicy) {
  for (GapPolicy policy : {GapPolicy::kRecord, GapPolicy::kRepeatCapture}) {
    Fixture f;
    bool dropped = false;
    EngineOptions opt;
    opt.gap_policy = policy;
    opt.on_progress = [&](const Progress& p) {
      if (p.phase == "capturing" && p.station_time_s > 1.0 && !dropped) {
        dropped = true;
        f.station.world().drop_samples(0, 7);
      }
    };
    RunEngine engine(f.station, f.journal, plan_of({capture(3.0)}), opt);
    EXPECT_EQ(engine.run(), RunState::kCompleted);
    EXPECT_TRUE(f.journal.has_event(EventKind::kFault, "7 samples missing"));
    if (policy == GapPolicy::kRecord) {
      EXPECT_TRUE(f.journal.discarded.empty());
    } else {
      EXPECT_EQ(f.journal.discarded.size(), 1u);
      EXPECT_EQ(f.journal.completed.back().second, 2);
    }
  }
}

TEST(RunEngine, StaleStreamIsAFaultAndInvalidatesTheCapture) {
  Fixture f;
  bool stalled = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.phase == "capturing" && !stalled) {
      stalled = true;
      f.station.world().set_imu_stalled(0, true);
    }
    if (stalled && p.station_time_s > 5.0) f.station.world().set_imu_stalled(0, false);
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(4.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_TRUE(f.journal.has_event(EventKind::kFault, "stream stale"));
  EXPECT_FALSE(f.journal.discarded.empty());
}

/// The simulated IMU as a streaming driver delivers it when a busy host holds its reader up for
/// longer than its clock estimate remembers (drivers::SampleClock): the samples taken from
/// `from_s` to `until_s` (device time) arrive `late_s` late and are stamped as they arrive;
/// those after come promptly but are stamped no earlier than the last (stamps never go back),
/// until their own time has caught up. The estimate comes back down: the stamps are set back.
class HeldUpImu final : public drivers::Imu {
 public:
  HeldUpImu(drivers::Imu& inner, core::Clock& clock) : inner_(inner), clock_(clock) {}
  double from_s = 1e300;
  double until_s = 1e300;
  double late_s = 0.0;
  double jump_from_s = 1e300;  ///< from this device time on, the unit's clock reads jump_s more
  double jump_s = 0.0;

  const std::string& name() const override { return inner_.name(); }
  drivers::Result configure() override { return inner_.configure(); }
  drivers::Result activate() override { return inner_.activate(); }
  drivers::Result deactivate() override { return inner_.deactivate(); }
  drivers::DeviceState state() const override { return inner_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override { return {}; }
  double sample_rate_hz() const override { return inner_.sample_rate_hz(); }
  std::uint64_t sequence_modulus() const override { return inner_.sequence_modulus(); }
  std::vector<core::ImuSample> poll() override {
    for (const auto& s : inner_.poll()) pending_.push_back(s);
    std::vector<core::ImuSample> out;
    while (!pending_.empty()) {
      core::ImuSample s = pending_.front();
      const bool held = s.device_time_s >= from_s && s.device_time_s < until_s;
      const double arrival_s = s.receive_time_s + (held ? late_s : 0.0);
      if (arrival_s > clock_.now_s()) break;  // in order: the held-up ones first
      s.receive_time_s = std::max(arrival_s, last_stamp_s_);
      last_stamp_s_ = s.receive_time_s;
      if (s.device_time_s >= jump_from_s) s.device_time_s += jump_s;
      out.push_back(s);
      pending_.pop_front();
    }
    return out;
  }

 private:
  drivers::Imu& inner_;
  core::Clock& clock_;
  std::deque<core::ImuSample> pending_;
  double last_stamp_s_ = -1e300;
};

/// The simulated station with its IMU behind HeldUpImu.
class StationWithAHeldUpImu final : public drivers::Station {
 public:
  StationWithAHeldUpImu() : imu_(sim_.imu(0), sim_.clock()) {}
  HeldUpImu& held_up() { return imu_; }
  const core::StationConfig& config() const override { return sim_.config(); }
  core::Clock& clock() override { return sim_.clock(); }
  drivers::Turntable& table() override { return sim_.table(); }
  drivers::Chamber& chamber() override { return sim_.chamber(); }
  std::size_t imu_count() const override { return 1; }
  drivers::Imu& imu(std::size_t) override { return imu_; }
  void wait_until(double t_s) override { sim_.wait_until(t_s); }

 private:
  drivers::SimStation sim_{sim::default_station()};
  HeldUpImu imu_;
};

// Stamped late, the samples of before the window (the end of a move, the last position) pass
// for the window's, and nothing else shows it: seen through the command-set drivers under
// load, a capture full of a move and a rate step's turns misattributed. Once the stamps are set
// back the capture is known bad: it is repeated (stale-stream policy), and the run says why.
TEST(RunEngine, SamplesStampedLateInvalidateTheCaptureWhenTheirStampsAreSetBack) {
  StationWithAHeldUpImu station;
  station.held_up().from_s = 0.5;
  station.held_up().until_s = 2.0;
  station.held_up().late_s = 0.5;  // less than the 1 s that makes a stream stale
  MemoryJournal journal;
  RunEngine engine(station, journal, plan_of({capture(3.0)}));
  EXPECT_EQ(engine.run(), RunState::kCompleted) << engine.exit_reason();
  EXPECT_TRUE(journal.has_event(EventKind::kFault, "time stamps set back"));
  EXPECT_FALSE(journal.has_event(EventKind::kFault, "stream stale"));
  ASSERT_EQ(journal.discarded.size(), 1u);
  EXPECT_EQ(journal.completed.back().second, 2);
  // The repeat waited for the stamps to hold (1 s here) after they were set back at 2 s, where
  // the reader catches up: an immediate one would be spent on a hold-up still draining.
  const auto repeat = journal.attempts.find({0, 2, station.imu(0).name()});
  ASSERT_NE(repeat, journal.attempts.end());
  EXPECT_GE(repeat->second.first_time_s, 2.0 + EngineOptions{}.stamps_hold_wall_s - 0.05);
}

TEST(RunEngine, TimeStampsThatHoldOrFollowADeviceClockJumpAreNotSetBack) {
  for (const double jump_s : {0.0, 1000.0}) {
    StationWithAHeldUpImu station;
    // The unit's clock leaps ahead mid-capture: station minus device time falls by the leap,
    // but the driver starts a new estimate (and reports the jump itself): no stamp was late.
    station.held_up().jump_from_s = 1.5;
    station.held_up().jump_s = jump_s;
    MemoryJournal journal;
    RunEngine engine(station, journal, plan_of({capture(3.0)}));
    EXPECT_EQ(engine.run(), RunState::kCompleted) << engine.exit_reason();
    EXPECT_FALSE(journal.has_event(EventKind::kFault, "time stamps set back")) << jump_s;
    EXPECT_TRUE(journal.discarded.empty()) << jump_s;
  }
}

TEST(RunEngine, StaleStreamOnlyRecordedWhenThePolicySaysSo) {
  Fixture f;
  bool stalled = false;
  core::FaultPolicy policy;
  policy.on_stale_stream = "record";
  EngineOptions opt = EngineOptions::from_policy(policy);
  opt.on_progress = [&](const Progress& p) {
    if (p.phase == "capturing" && !stalled) {
      stalled = true;
      f.station.world().set_imu_stalled(0, true);
    }
    if (stalled && p.station_time_s > 3.0) f.station.world().set_imu_stalled(0, false);
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(4.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_TRUE(f.journal.has_event(EventKind::kFault, "stream stale"));
  EXPECT_TRUE(f.journal.discarded.empty());
  EXPECT_THROW(parse_gap_policy("ignore"), std::invalid_argument);
}

TEST(RunEngine, SimulatedTimeWaitsForTheWriterInsteadOfOverflowing) {
  Fixture f;
  f.journal.refuse_samples_until_wait = true;
  RunEngine engine(f.station, f.journal, plan_of({capture(2.0)}));
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_EQ(f.journal.waits, 1);
  EXPECT_TRUE(f.journal.discarded.empty());
  EXPECT_FALSE(f.journal.has_event(EventKind::kFault, "overflow"));
}

TEST(RunEngine, WriterOverflowIsAFaultThatInvalidatesTheCapture) {
  Fixture f;
  f.journal.refuse_samples = true;
  EngineOptions opt;
  opt.max_capture_attempts = 2;
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0)}), opt);
  EXPECT_EQ(engine.run(), RunState::kFailed);
  EXPECT_TRUE(f.journal.has_event(EventKind::kFault, "overflow"));
  EXPECT_EQ(f.journal.discarded.size(), 2u);
}

TEST(RunEngine, ResumeReestablishesTemperatureAndPositionThenSkipsDoneSteps) {
  Fixture f;
  bool checked = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.phase != "capturing" || checked) return;
    checked = true;
    EXPECT_NEAR(std::abs(f.station.table().read_state().outer.angle_deg), 180.0, 1e-3);
    EXPECT_NEAR(f.station.chamber().read_state().air_temperature_c, 35.0, 0.5);
  };
  RunEngine engine(f.station, f.journal,
                   plan_of({temperature(35.0), move(180.0, 0.0), capture(2.0), capture(2.0)}), opt);
  EXPECT_EQ(engine.run(2, 3), RunState::kCompleted);
  EXPECT_TRUE(checked);
  // Steps 0 and 1 are not started again, but their state is: captures at 35 degC, upside down.
  for (const auto& [step, attempt] : f.journal.started) EXPECT_GE(step, 2u);
  EXPECT_EQ(f.journal.completed.front(), std::make_pair(std::size_t{2}, 3));
  EXPECT_TRUE(f.journal.has_event(EventKind::kInfo, "resuming at step 2"));
}

TEST(RunEngine, SkipDuringACaptureDiscardsItAndGoesOn) {
  Fixture f;
  RunEngine* e = nullptr;
  bool skipped_once = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing" && p.station_time_s > 2.0 && !skipped_once) {
      skipped_once = true;
      e->skip("sensor warming up", "alice");
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(30.0), capture(1.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.skipped.size(), 1u);
  EXPECT_EQ(f.journal.skipped[0].first, 1u);
  EXPECT_EQ(f.journal.skipped[0].second, "skipped by alice: sensor warming up");
  // The interrupted attempt is gone; the steps either side completed.
  ASSERT_EQ(f.journal.discarded.size(), 1u);
  EXPECT_EQ(f.journal.discarded[0].first, 1u);
  EXPECT_EQ(samples_of(f.journal, 1), 0u);
  ASSERT_EQ(f.journal.completed.size(), 2u);
  EXPECT_EQ(f.journal.completed[0].first, 0u);
  EXPECT_EQ(f.journal.completed[1].first, 2u);
  EXPECT_TRUE(
      f.journal.has_event(EventKind::kOperator, "alice: skip requested: sensor warming up"));
  // Far less than the 30 s capture passed.
  EXPECT_LT(f.station.clock().now_s(), 10.0);
}

TEST(RunEngine, SkippedRateStepLeavesTheTableAtRest) {
  Fixture f;
  RunEngine* e = nullptr;
  double rate_when_next_step_ran = -1.0;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 0 && p.phase == "capturing" && f.journal.skipped.empty()) e->skip("enough");
    if (p.step == 1 && p.phase == "capturing") {
      rate_when_next_step_ran =
          std::abs(f.station.table().read_state().inner.rate_dps);  // the last one stays
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({rate("inner", 60.0, 100.0), capture(3.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.skipped.size(), 1u);
  EXPECT_EQ(f.journal.skipped[0].first, 0u);
  // Commanded to rest when skipped: by the end of the 3 s capture after it the axis has
  // stopped (a skipped step without the rest command would leave it at 60 deg/s).
  EXPECT_GE(rate_when_next_step_ran, 0.0);
  EXPECT_LT(rate_when_next_step_ran, 0.01);
  EXPECT_NEAR(f.station.table().read_state().inner.rate_dps, 0.0, 1e-6);
}

TEST(RunEngine, SkipWhilePausedSkipsTheNextStepAndStaysPaused) {
  Fixture f;
  RunEngine* e = nullptr;
  int paused_ticks = 0;
  bool pause_asked = false, skipped = false;
  EngineOptions opt;
  opt.paused_real_sleep_s = 0.0;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 0 && p.phase == "capturing" && !pause_asked) {
      pause_asked = true;
      e->pause(false);
    }
    if (p.state != RunState::kPaused) return;
    ++paused_ticks;
    if (!skipped) {
      EXPECT_EQ(p.step, 1u);  // paused before step 1: that is the one a skip skips
      skipped = true;
      e->skip("not needed today");
    } else if (paused_ticks > 20) {
      e->resume();
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(1.0), capture(1.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  ASSERT_EQ(f.journal.skipped.size(), 1u);
  EXPECT_EQ(f.journal.skipped[0].first, 1u);
  EXPECT_GT(paused_ticks, 20);  // still paused after the skip, until the resume
  ASSERT_EQ(f.journal.completed.size(), 2u);
  EXPECT_EQ(f.journal.completed[1].first, 2u);
  EXPECT_TRUE(f.journal.discarded.empty());  // step 1 never started
  // Paused once, resumed once: the skip did not record a second pause.
  EXPECT_EQ(std::count(f.journal.states.begin(), f.journal.states.end(), RunState::kPaused), 1);
}

TEST(RunEngine, SkipMeantForAStepThatHasEndedIsNotApplied) {
  Fixture f;
  RunEngine* e = nullptr;
  bool asked = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing" && !asked) {
      asked = true;
      e->skip("late", "bob", 0);  // the operator saw step 0; it has already ended
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(2.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_TRUE(f.journal.skipped.empty());
  EXPECT_EQ(f.journal.completed.size(), 2u);
  EXPECT_TRUE(f.journal.has_event(EventKind::kInfo, "skip of step 0 not applied"));
}

// Operator requests that arrive while a resumed run re-establishes its temperature and position
// wait for the first step: a pause at once then pauses it (before that, it crashed the daemon).
TEST(RunEngine, PauseAtOnceWhileReestablishingPausesTheFirstStep) {
  Fixture f;
  RunEngine* e = nullptr;
  bool asked = false;
  EngineOptions opt;
  opt.paused_real_sleep_s = 0.0;
  opt.on_progress = [&](const Progress& p) {
    if (!asked && (p.phase == "soaking" || p.phase == "moving")) {
      asked = true;
      e->pause(true);
      e->skip("also wait");
    }
    if (p.state == RunState::kPaused) e->resume();
  };
  RunEngine engine(f.station, f.journal,
                   plan_of({temperature(35.0), move(180.0, 0.0), capture(2.0), capture(2.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(2, 3), RunState::kCompleted);
  EXPECT_TRUE(asked);
  EXPECT_TRUE(f.journal.has_event(EventKind::kInfo, "resuming at step 2"));
  EXPECT_NE(std::find(f.journal.states.begin(), f.journal.states.end(), RunState::kPaused),
            f.journal.states.end());
  // The skip applied to step 2 (the first step), not to the re-established ones.
  ASSERT_EQ(f.journal.skipped.size(), 1u);
  EXPECT_EQ(f.journal.skipped[0].first, 2u);
  EXPECT_EQ(f.journal.completed.back().first, 3u);
}

// After a restart the station is re-established from the steps that completed: a temperature
// the operator skipped (say the chamber could not reach it) is not commanded again.
TEST(RunEngine, ResumeDoesNotReestablishASkippedTemperature) {
  Fixture f;
  double setpoint_at_capture = 0.0;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.phase == "capturing" && setpoint_at_capture == 0.0) {
      setpoint_at_capture = f.station.chamber().read_state().setpoint_c;
    }
  };
  RunEngine engine(f.station, f.journal,
                   plan_of({temperature(35.0), move(90.0, 0.0), temperature(80.0), capture(2.0)}),
                   opt);
  EXPECT_EQ(engine.run(3, 1, {2}), RunState::kCompleted);
  EXPECT_NEAR(setpoint_at_capture, 35.0, 1e-9);
}

// Requests wait in the engine's queue and are applied in the order they came: a pause and an
// abort arriving together are both recorded, pause first, and the abort ends the run (an
// abort is checked before a pause at every tick, so the run is never seen paused).
TEST(RunEngine, PauseThenAbortArrivingTogetherEndAborted) {
  Fixture f;
  RunEngine* e = nullptr;
  bool asked = false;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing" && !asked) {
      asked = true;
      e->pause(true, "bob");
      e->abort("smoke", "alice");
    }
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(60.0), capture(1.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kAborted);
  EXPECT_EQ(engine.exit_reason(), "aborted by alice: smoke");
  std::vector<std::string> operator_events;
  for (const auto& [kind, message] : f.journal.events) {
    if (kind == EventKind::kOperator) operator_events.push_back(message);
  }
  EXPECT_EQ(operator_events, (std::vector<std::string>{"bob: pause requested (at once)",
                                                       "alice: abort requested: smoke"}));
  EXPECT_EQ(std::count(f.journal.states.begin(), f.journal.states.end(), RunState::kPaused), 0);
  EXPECT_EQ(f.journal.completed.size(), 1u);
}

// A checkpoint (interrupt) and an operator's abort together: whichever came first, the run
// ends aborted, as an operator's abort is never turned into a resumable checkpoint.
TEST(RunEngine, AnAbortWinsOverACheckpointInEitherOrder) {
  for (const bool interrupt_first : {true, false}) {
    Fixture f;
    RunEngine* e = nullptr;
    bool asked = false;
    EngineOptions opt;
    opt.on_progress = [&](const Progress& p) {
      if (p.phase != "capturing" || asked) return;
      asked = true;
      if (interrupt_first) e->interrupt("daemon stopping");
      e->abort("wrong unit", "alice");
      if (!interrupt_first) e->interrupt("daemon stopping");
    };
    RunEngine engine(f.station, f.journal, plan_of({capture(60.0)}), opt);
    e = &engine;
    EXPECT_EQ(engine.run(), RunState::kAborted)
        << (interrupt_first ? "interrupt first" : "abort first");
    EXPECT_EQ(engine.exit_reason(), "aborted by alice: wrong unit");
    // An interrupt after the abort is dropped without a word; one before it was recorded.
    EXPECT_EQ(f.journal.has_event(EventKind::kOperator, "interrupt requested"), interrupt_first);
  }
}

TEST(RunEngine, ACheckpointAloneEndsTheRunInterrupted) {
  Fixture f;
  RunEngine* e = nullptr;
  EngineOptions opt;
  opt.on_progress = [&](const Progress& p) {
    if (p.step == 1 && p.phase == "capturing") e->interrupt("daemon stopping");
  };
  RunEngine engine(f.station, f.journal, plan_of({capture(1.0), capture(60.0)}), opt);
  e = &engine;
  EXPECT_EQ(engine.run(), RunState::kInterrupted);
  EXPECT_EQ(f.journal.completed.size(), 1u);  // the cut capture stays unfinished
}

// Requests pushed to a shared queue from another thread before the run starts are taken by
// the engine at its first step boundary, in order.
TEST(RunEngine, RequestsQueuedBeforeTheRunAreTakenAtTheFirstBoundary) {
  Fixture f;
  auto commands = std::make_shared<EngineCommandQueue>();
  std::thread([&] {
    commands->push({EngineCommand::Kind::kSkip, false, 0, "not needed", "carol"});
    commands->push({EngineCommand::Kind::kAbort, false, std::nullopt, "changed my mind", "carol"});
  }).join();
  RunEngine engine(f.station, f.journal, plan_of({capture(5.0), capture(5.0)}), {}, commands);
  EXPECT_EQ(engine.run(), RunState::kAborted);
  EXPECT_EQ(engine.exit_reason(), "aborted by carol: changed my mind");
  EXPECT_TRUE(
      f.journal.has_event(EventKind::kOperator, "carol: skip of step 0 requested: not needed"));
  EXPECT_TRUE(f.journal.completed.empty());
  EXPECT_TRUE(commands->take_all().empty());  // the engine took both
}

// ---- power steps ---------------------------------------------------------------------------

Step power(bool on, double settle_s, std::string imu = {}) {
  Step s;
  s.kind = StepKind::kPower;
  s.label = on ? "power on" : "power off";
  s.power_on = on;
  s.settle_s = settle_s;
  s.imu = std::move(imu);
  return s;
}

core::StationConfig station_with_supply_safe(const std::string& safe_state) {
  core::StationConfig c = sim::default_station();
  c.power_supplies.at(0).safe_state = safe_state;
  return c;
}

TEST(RunEngine, PowerStepsCycleTheUnitAndTheCaptureAfterwardsIsWhole) {
  drivers::SimStation station(station_with_supply_safe("off"));
  MemoryJournal journal;
  const double bias_before = station.world().imu(0).turn_on_gyro_bias().x();
  RunEngine engine(
      station, journal,
      plan_of({capture(1.0), power(false, 5.0), power(true, 2.0, "imu0"), capture(2.0)}));
  EXPECT_EQ(engine.run(), RunState::kCompleted) << engine.exit_reason();
  EXPECT_EQ(journal.completed.size(), 4u);
  EXPECT_NE(station.world().imu(0).turn_on_gyro_bias().x(), bias_before)
      << "a new turn-on bias after the power cycle";
  EXPECT_NEAR(static_cast<double>(samples_of(journal, 3)), 800.0, 1.0);
  EXPECT_TRUE(journal.has_event(EventKind::kInfo, "imu0 powered off"));
  EXPECT_TRUE(journal.has_event(EventKind::kInfo, "imu0 powered on"));
  EXPECT_FALSE(journal.has_event(EventKind::kFault, "stream stale"))
      << "a unit switched off is not a stale stream";
  EXPECT_FALSE(journal.has_event(EventKind::kFault, "gap")) << "its restart is no sequence gap";
  EXPECT_FALSE(station.world().imu_powered(0)) << "safe state \"off\" switches the supply off";
}

// The unit's start limit is its supply's start_timeout_s (station file): the run waits that long
// in station time, then fails to the safe state naming the unit and the limit.
TEST(RunEngine, AUnitThatDoesNotComeBackFailsTheRunSafeWithTheReason) {
  core::StationConfig config = station_with_supply_safe("off");
  config.power_supplies.at(0).start_timeout_s = 3.0;
  drivers::SimStation station(config);
  MemoryJournal journal;
  station.world().set_imu_stalled(0, true);  // powered, but its stream never starts
  RunEngine engine(station, journal, plan_of({power(false, 1.0), power(true, 1.0), capture(1.0)}));
  const double off_s = station.clock().now_s();
  EXPECT_EQ(engine.run(), RunState::kFailed);
  EXPECT_EQ(engine.exit_reason(),
            "imu0 did not start streaming within 3 s after power on (its supply's "
            "start_timeout_s)");
  // 1 s off, then 3 s waiting for the stream (and the safe state's own time).
  EXPECT_GE(station.clock().now_s() - off_s, 4.0);
  EXPECT_LT(station.clock().now_s() - off_s, 10.0);
  EXPECT_EQ(journal.completed.size(), 1u);
  EXPECT_FALSE(station.world().imu_powered(0)) << "the safe state switched the supply off";
  EXPECT_EQ(station.chamber().read_state().mode, core::ChamberMode::kStandby);
}

TEST(RunEngine, SafeStateOnLeavesTheSupplyOn) {
  drivers::SimStation station(station_with_supply_safe("on"));
  MemoryJournal journal;
  RunEngine engine(station, journal, plan_of({power(false, 1.0), power(true, 1.0)}));
  EXPECT_EQ(engine.run(), RunState::kCompleted);
  EXPECT_TRUE(station.world().imu_powered(0));
}

}  // namespace
}  // namespace calstand::daemon

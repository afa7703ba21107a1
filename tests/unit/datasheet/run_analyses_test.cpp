// Which datasheet analyses a run supports, from its step records alone: each procedure shape of
// the test catalogue makes its own analysis apply and no other, steps that did not complete do
// not count, and a record from power-up is the warm-up's, not in-run stability.
#include "datasheet/run_analyses.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace calstand::analysis {
namespace {

class Steps {
 public:
  Steps& add(const std::string& kind, nlohmann::json commanded, double length_s = 1.0,
             store::StepStatus status = store::StepStatus::kCompleted) {
    store::StepRecord s;
    s.index = steps_.size();
    s.kind = kind;
    s.label = kind + " " + std::to_string(s.index);
    s.commanded = std::move(commanded);
    s.status = status;
    s.started_clock_s = clock_s_;
    clock_s_ += length_s;
    s.ended_clock_s = clock_s_;
    steps_.push_back(std::move(s));
    return *this;
  }
  Steps& power(bool on, double settle_s) {
    return add("power", {{"power", on ? "on" : "off"}, {"settle_s", settle_s}}, settle_s);
  }
  Steps& capture(double length_s) { return add("capture", {{"duration_s", length_s}}, length_s); }
  Steps& set_temperature(double target_c) {
    return add("set_temperature", {{"target_c", target_c}}, 600.0);
  }
  const std::vector<store::StepRecord>& records() const { return steps_; }

 private:
  std::vector<store::StepRecord> steps_;
  double clock_s_ = 0.0;
};

std::vector<DatasheetKind> applying(const std::vector<store::StepRecord>& steps) {
  std::vector<DatasheetKind> out;
  for (const auto& a : datasheet_applicability(steps)) {
    if (a.applies) out.push_back(a.kind);
  }
  return out;
}

const DatasheetApplicability& of(const std::vector<DatasheetApplicability>& all,
                                 DatasheetKind kind) {
  return all.at(static_cast<std::size_t>(kind));
}

TEST(DatasheetApplicability, OneEntryPerKindInPageOrder) {
  const auto all = datasheet_applicability({});
  ASSERT_EQ(all.size(), kDatasheetKinds.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].kind, kDatasheetKinds[i]);
    EXPECT_FALSE(all[i].applies) << to_string(all[i].kind);
    EXPECT_FALSE(all[i].evidence.empty()) << "says what the run lacks";
  }
}

TEST(DatasheetApplicability, PowerCyclesWithSettledCapturesAreRepeatabilityOnly) {
  Steps s;
  s.add("move", {{"up", "+z"}});
  for (int cycle = 0; cycle < 3; ++cycle) s.power(false, 30).power(true, 300).capture(120);
  EXPECT_EQ(applying(s.records()), std::vector<DatasheetKind>{DatasheetKind::kRepeatability});
  EXPECT_NE(of(datasheet_applicability(s.records()), DatasheetKind::kRepeatability)
                .evidence.find("3 power-ups"),
            std::string::npos);
  // One power-up is no repeatability.
  Steps once;
  once.power(false, 30).power(true, 300).capture(120);
  const auto one = datasheet_applicability(once.records());
  EXPECT_FALSE(of(one, DatasheetKind::kRepeatability).applies);
  EXPECT_NE(of(one, DatasheetKind::kRepeatability).evidence.find("two or more"), std::string::npos);
}

TEST(DatasheetApplicability, ARecordFromPowerUpIsTheWarmUpNotInRunStability) {
  Steps s;
  s.add("move", {{"up", "+z"}}).power(false, 1800).power(true, 0).capture(3600);
  const auto all = datasheet_applicability(s.records());
  EXPECT_EQ(applying(s.records()), std::vector<DatasheetKind>{DatasheetKind::kWarmup});
  EXPECT_EQ(of(all, DatasheetKind::kWarmup).step, std::optional<std::size_t>(3));
  EXPECT_NE(of(all, DatasheetKind::kStability).evidence.find("warm-up"), std::string::npos);
  // A settle time before recording: no longer from power-up.
  Steps settled;
  settled.power(false, 1800).power(true, 300).capture(3600);
  const auto later = datasheet_applicability(settled.records());
  EXPECT_FALSE(of(later, DatasheetKind::kWarmup).applies);
  EXPECT_TRUE(of(later, DatasheetKind::kStability).applies);
  EXPECT_EQ(of(later, DatasheetKind::kStability).step, std::optional<std::size_t>(2));
}

TEST(DatasheetApplicability, StabilityNeedsTheLongestStaticCaptureLongEnough) {
  Steps s;
  s.capture(60).capture(700).capture(100);
  const auto all = datasheet_applicability(s.records());
  EXPECT_EQ(applying(s.records()), std::vector<DatasheetKind>{DatasheetKind::kStability});
  EXPECT_EQ(of(all, DatasheetKind::kStability).step, std::optional<std::size_t>(1));
  Steps short_run;
  short_run.capture(60).capture(300);
  const auto none = datasheet_applicability(short_run.records());
  EXPECT_FALSE(of(none, DatasheetKind::kStability).applies);
  EXPECT_NE(of(none, DatasheetKind::kStability).evidence.find("300 s"), std::string::npos);
}

TEST(DatasheetApplicability, HysteresisNeedsASetPointWithCapturesReachedFromBothSides) {
  Steps staircase;
  for (const double t : {10.0, 40.0, 70.0, 40.0, 10.0}) {
    staircase.set_temperature(t).capture(60).capture(60);
  }
  const auto all = datasheet_applicability(staircase.records());
  EXPECT_EQ(applying(staircase.records()), std::vector<DatasheetKind>{DatasheetKind::kHysteresis});
  // 10 degC is first reached from wherever the chamber was: only 40 is known from both sides.
  EXPECT_NE(of(all, DatasheetKind::kHysteresis).evidence.find("40 degC"), std::string::npos);
  EXPECT_EQ(of(all, DatasheetKind::kHysteresis).evidence.find("10"), std::string::npos);
  // A thermal calibration visits each plateau once.
  Steps plateaus;
  for (const double t : {-40.0, 25.0, 85.0}) plateaus.set_temperature(t).capture(60);
  EXPECT_TRUE(applying(plateaus.records()).empty());
}

TEST(DatasheetApplicability, OnlyCompletedStepsCount) {
  Steps s;
  s.add("oscillate", {{"frequency_hz", 5.0}}, 4.0, store::StepStatus::kFailed)
      .add("capture", {{"duration_s", 900.0}}, 900.0, store::StepStatus::kSkipped);
  EXPECT_TRUE(applying(s.records()).empty());
  s.add("oscillate", {{"frequency_hz", 5.0}}, 4.0);
  EXPECT_EQ(applying(s.records()), std::vector<DatasheetKind>{DatasheetKind::kBandwidth});
}

TEST(DatasheetApplicability, KindsAreTheAnalyzeCommandsNames) {
  std::vector<std::string> names;
  for (const auto kind : kDatasheetKinds) names.emplace_back(to_string(kind));
  EXPECT_EQ(names, (std::vector<std::string>{"repeatability", "warmup", "stability", "hysteresis",
                                             "bandwidth"}));
}

}  // namespace
}  // namespace calstand::analysis

#include "tablefree/ferraris.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "session_truth.hpp"
#include "sim/hand_session.hpp"

namespace calstand::solver {
namespace {

sim::SimSession ferraris_session(const char* spec, std::uint64_t seed, double angle = 360.0) {
  sim::FerrarisSessionOptions o;
  o.imu.spec = spec;
  o.imu.sample_rate_hz = 200.0;
  o.turn_angle_deg = angle;
  return sim::simulate_ferraris_session(o, seed);
}

FerrarisResult ferraris_fit(const sim::SimSession& s, FerrarisOptions o = {}) {
  o.gravity_mps2 = s.gravity_mps2;
  const auto sections = ferraris_sections_from_steps(s.steps, s.step_labels);
  return calibrate_ferraris(s.samples, sections, o);
}

// Holds placed by hand with ~1 deg of tilt: taken as exact they give chi2/dof in the
// hundred-thousands and misalignment sigmas a hundred times too small (the naive pulls below
// are far beyond 4: the check can fail); with the placement variance estimated, chi2/dof is 1,
// the scatter is found, and every parameter is within its sigmas.
TEST(Ferraris, PlacementErrorIsEstimatedNotMistakenForAnEffect) {
  std::vector<testing::Pull> all;
  double naive_worst = 0.0;
  for (const char* spec : {"adis16488", "ln200"}) {
    for (std::uint64_t seed : {31, 32, 33}) {
      SCOPED_TRACE(std::string(spec) + " seed " + std::to_string(seed));
      const sim::SimSession s = ferraris_session(spec, seed);
      const FerrarisResult r = ferraris_fit(s);
      FerrarisOptions naive_options;
      naive_options.estimate_placement = false;
      const FerrarisResult naive = ferraris_fit(s, naive_options);

      EXPECT_GT(r.accel_chi2_per_dof_naive, 1000.0);
      EXPECT_NEAR(r.accel_chi2_per_dof, 1.0, 1e-6);
      EXPECT_TRUE(r.placement_estimated);
      double true_sq = 0.0;
      for (const sim::SessionHold& h : s.holds)
        true_sq += h.placement_tilt_deg * h.placement_tilt_deg;
      const double true_rms = std::sqrt(true_sq / 6.0);
      EXPECT_GT(r.placement_rms_tilt_deg, 0.4 * true_rms);
      EXPECT_LT(r.placement_rms_tilt_deg, 2.5 * true_rms);
      EXPECT_NE(r.summary.find("placed with a scatter of"), std::string::npos);

      for (const testing::Pull& p : testing::session_pulls(s, r.parameters)) {
        EXPECT_LT(std::abs(p.pull), 4.0) << p.name;
        all.push_back(p);
      }
      for (const testing::Pull& p : testing::session_pulls(s, naive.parameters)) {
        if (p.name.find("misalignment") != std::string::npos) {
          naive_worst = std::max(naive_worst, std::abs(p.pull));
        }
      }
      // The misalignment sigmas reflect the placement: of the order of its scatter.
      for (const TriadEstimate& e : r.parameters) {
        if (e.status == EstimateStatus::kEstimated && e.unit == "rad") {
          EXPECT_GT(e.sigma, 0.2 * r.placement_sigma_deg * core::kDegToRad) << e.name;
        }
      }
    }
  }
  EXPECT_GT(naive_worst, 20.0);
  ASSERT_EQ(all.size(), 6U * 21U);
  const double rms = testing::rms_pull(all);
  EXPECT_GT(rms, 0.4);
  EXPECT_LT(rms, 1.5);
}

TEST(Ferraris, TurnSignFromTheData) {
  // Turned clockwise (-360 about each axis) while the sections say nothing (default +360).
  const sim::SimSession s = ferraris_session("ln200", 34, -360.0);
  const FerrarisResult r = ferraris_fit(s);
  ASSERT_EQ(r.turns.size(), 3U);
  for (const FerrarisTurn& t : r.turns) {
    EXPECT_NEAR(t.measured_angle_deg, -360.0, 5.0);
    EXPECT_EQ(t.used_angle_deg, -360.0);
  }
  ASSERT_EQ(r.notes.size(), 3U);
  EXPECT_NE(r.notes[0].find("(the label says +360)"), std::string::npos) << r.notes[0];
  for (const testing::Pull& p : testing::session_pulls(s, r.parameters)) {
    EXPECT_LT(std::abs(p.pull), 4.0) << p.name;
  }
  // Taking the label's sign as given makes the gyro read backwards, and says so.
  FerrarisOptions given;
  given.turn_sign = TurnSign::kGiven;
  const FerrarisResult g = ferraris_fit(s, given);
  EXPECT_NEAR(g.gyro_nominal_frame.scale_ppm.x(), -2e6, 2e4);
  ASSERT_FALSE(g.notes.empty());
  EXPECT_NE(g.notes[0].find("near -1"), std::string::npos) << g.notes[0];
}

TEST(Ferraris, RefusesIncompleteSessions) {
  const sim::SimSession s = ferraris_session("ln200", 35);
  auto sections = ferraris_sections_from_steps(s.steps, s.step_labels);
  FerrarisOptions o;
  o.gravity_mps2 = s.gravity_mps2;
  auto missing = sections;
  missing.erase(missing.begin() + 7);  // y_rot
  try {
    calibrate_ferraris(s.samples, missing, o);
    FAIL() << "a session without y_rot was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("y_rot"), std::string::npos) << e.what();
  }
  auto unknown = sections;
  unknown[0].label = "x_up";
  EXPECT_THROW(calibrate_ferraris(s.samples, unknown, o), core::InputError);
  auto twice = sections;
  twice.push_back(sections[0]);
  EXPECT_THROW(calibrate_ferraris(s.samples, twice, o), core::InputError);
  const std::vector<int> steps(10, 1);
  EXPECT_THROW(ferraris_sections_from_steps(steps, {{2, "x_p"}}), core::InputError);
}

TEST(Ferraris, Json) {
  const FerrarisResult r = ferraris_fit(ferraris_session("adis16488", 36));
  const nlohmann::json j = ferraris_to_json(r);
  EXPECT_EQ(j["method"], "ferraris");
  EXPECT_EQ(j["parameters"].size(), 24U);
  EXPECT_EQ(j["covariance"]["matrix"].size(), 24U);
  EXPECT_EQ(j["holds"].size(), 6U);
  EXPECT_EQ(j["turns"].size(), 3U);
  EXPECT_TRUE(j["placement"]["estimated"].get<bool>());
  EXPECT_TRUE(j["nominal_frame"]["accel"].contains("matrix"));
}

}  // namespace
}  // namespace calstand::solver

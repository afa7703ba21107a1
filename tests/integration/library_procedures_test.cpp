// Each shipped procedure determines what it is documented to determine: it runs in process on
// the embedded simulated station (its LN200-class IMU drawn from the datasheet: turn-on bias,
// bias instability, random walks, vibration sensitivity) through the engine and store of
// `calstand run`, is fitted with the model its description names, and exactly the parameters
// the description leaves out are reported as not determined. Parameters are reduced (shorter
// captures, fewer rates and plateaus) so that a procedure takes a second or two; the reductions
// keep every leg of a procedure, so they excite the same body axes as its defaults.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "datasheet/bandwidth.hpp"
#include "in_process_run.hpp"
#include "noise/run_noise.hpp"
#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"

namespace calstand {
namespace {

/// One library procedure and what its description says it determines.
struct Documented {
  std::string procedure;
  std::vector<std::string> overrides;  ///< `--set` reductions for speed
  std::string model;                   ///< the terms its description names
  std::vector<std::string> customs;    ///< custom terms (NAME=SENSOR:EXPR)
  /// Exactly the parameters of `model` the description says the procedure does not determine.
  std::set<std::string> not_determined;
};

std::ostream& operator<<(std::ostream& os, const Documented& d) { return os << d.procedure; }

std::set<std::string> components(const std::string& term, const std::vector<std::string>& axes) {
  std::set<std::string> out;
  for (const auto& a : axes) out.insert(term + "." + a);
  return out;
}

std::string listed(const std::set<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

using testing::fresh_db;
using testing::remove_db;
using testing::run_procedure;

class LibraryProcedure : public ::testing::TestWithParam<Documented> {};

TEST_P(LibraryProcedure, DeterminesExactlyWhatItsDescriptionSays) {
  const Documented& d = GetParam();
  const std::string db_path = fresh_db(d.procedure);
  const std::int64_t run_id = run_procedure(d.procedure, d.overrides, db_path);
  if (HasFailure()) return;
  store::Database db(db_path);
  const solver::Model model = solver::Model::parse(d.model, d.customs);
  const auto steps = solver::summarize_steps(solver::load_run_data(db, run_id), model);
  const solver::FitResult fit = solver::fit_model(steps, model, solver::measure_noise_floor(steps));

  std::set<std::string> not_determined;
  std::ostringstream reasons;
  reasons << " (temperature plateaus:";
  for (const double t : solver::temperature_plateaus(steps)) reasons << " " << t;
  reasons << " degC)";
  for (const auto& u : fit.unidentifiable) {
    not_determined.insert(u.name);
    reasons << "\n  " << u.name << ": " << u.reason;
  }
  std::set<std::string> claimed_but_not, disclaimed_but_determined;
  for (const auto& n : not_determined)
    if (!d.not_determined.count(n)) claimed_but_not.insert(n);
  for (const auto& n : d.not_determined)
    if (!not_determined.count(n)) disclaimed_but_determined.insert(n);
  EXPECT_TRUE(claimed_but_not.empty())
      << d.procedure << " does not determine " << listed(claimed_but_not)
      << ", which its description claims:" << reasons.str();
  EXPECT_TRUE(disclaimed_but_determined.empty())
      << d.procedure << " determines " << listed(disclaimed_but_determined)
      << ", which its description says it does not (update the description)";
  EXPECT_EQ(fit.parameters.size() + fit.unidentifiable.size(), model.size());
  remove_db(db_path);
}

// Body axes on the default table (outer axis North, inner axis Up at (0, 0)): with the inner
// axis at 0 the outer axis is body y, at 90 body x; the inner axis is always body z. A static
// test sees the gyros' scale factors and misalignments through the Earth rate alone (their
// sigmas are near the bounds the fit calls implausible, so whether they count as determined
// depends on capture lengths): the static models leave them out, as the descriptions do.
INSTANTIATE_TEST_SUITE_P(
    Library, LibraryProcedure,
    ::testing::Values(
        // Only z is turned over: the x and y accelerometers never see gravity.
        Documented{"two-position",
                   {"capture_s=10"},
                   "gyro_bias,earth_rate,accel_bias,accel_scale",
                   {},
                   components("accel_scale", {"x", "y"})},
        Documented{"six-position",
                   {"capture_s=10"},
                   "gyro_bias,earth_rate,accel_bias,accel_scale,accel_misalignment",
                   {},
                   {}},
        Documented{"twelve-position",
                   {"capture_s=10"},
                   "gyro_bias,earth_rate,accel_bias,accel_scale,accel_misalignment",
                   {},
                   {}},
        Documented{"multi-position",
                   {"capture_s=10"},
                   "gyro_bias,earth_rate,gyro_g_sensitivity,accel_bias,accel_scale,"
                   "accel_misalignment,accel_quadratic",
                   {},
                   {}},
        // A gyro test: the accelerometers' rows get their biases so that the fit models them.
        Documented{"rate-ladder",
                   {"rates=[20,100]", "revolutions=1"},
                   "gyro_bias,gyro_scale,gyro_misalignment,gyro_scale_asymmetry,gyro_quadratic,"
                   "earth_rate,accel_bias",
                   {},
                   {}},
        // Reduced as tests/integration/campaign_test.cpp does: two plateaus (temperature order 1).
        Documented{"thermal-calibration",
                   {"temperatures=[15,35]", "soak_s=300", "capture_s=4", "outer_angles=[0,90,180]",
                    "inner_angles=[0,90]", "rates=[20,90]", "revolutions=1", "ramp_c_per_min=2"},
                   "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,"
                   "accel_misalignment,gyro_temp_bias,accel_temp_bias,gyro_temp_scale,"
                   "accel_temp_scale",
                   {},
                   {}},
        // Two 20 degC ramps with the table indexing through the six positions and turning
        // about each body axis: the classical model with bias curves of order 2 and linear
        // scale terms; a bias still differing between heating and cooling follows the
        // temperature rate.
        Documented{"thermal-ramp",
                   {"low_c=15", "high_c=35", "ramp_c_per_min=1", "cycles=10", "capture_s=10",
                    "rates=[60]", "soak_s=300"},
                   "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,"
                   "accel_misalignment,gyro_temp_bias:2,accel_temp_bias:2,gyro_temp_scale,"
                   "accel_temp_scale,gyro_lag,accel_lag",
                   {"gyro_lag=gyro:temperature_rate", "accel_lag=accel:temperature_rate"},
                   {}}),
    [](const auto& param_info) {  // not `info`: the macro's own parameter (-Wshadow)
      std::string n = param_info.param.procedure;
      std::erase(n, '-');
      return n;
    });

// static-allan is documented for noise analysis, not for an error model: its one capture gives
// the white-noise figures of the datasheet (ARW 0.07 deg/sqrt(h); 50 ug/sqrt(Hz), i.e. VRW
// 0.0294 m/s/sqrt(h)), and even a fit of the biases alone has no redundancy to be judged by.
TEST(LibraryStaticAllan, DeterminesTheNoiseFiguresAndNoErrorModel) {
  const std::string db_path = fresh_db("static-allan");
  const std::int64_t run_id =
      run_procedure("static-allan", {"duration_s=600", "soak_s=1", "warmup_s=1"}, db_path);
  if (HasFailure()) return;
  store::Database db(db_path);
  const solver::RunNoise noise = solver::analyse_run_noise(db, run_id);
  ASSERT_EQ(noise.channels.size(), 6u);
  for (const auto& channel : noise.channels) {
    const bool gyro = solver::is_gyro(channel.channel);
    const std::string want = gyro ? "angle_random_walk" : "velocity_random_walk";
    const double datasheet = gyro ? 0.07 : 0.0294;
    int found = 0;
    for (const auto& f : channel.figures) {
      if (f.name != want) continue;
      ++found;
      EXPECT_TRUE(f.resolved) << solver::to_string(channel.channel);
      EXPECT_NEAR(f.value, datasheet, 0.2 * datasheet)
          << solver::to_string(channel.channel) << " " << want << " [" << f.unit << "]";
    }
    EXPECT_EQ(found, 1) << solver::to_string(channel.channel) << ": " << want;
  }
  const solver::Model model = solver::Model::parse("gyro_bias,earth_rate,accel_bias");
  const auto steps = solver::summarize_steps(solver::load_run_data(db, run_id), model);
  EXPECT_THROW((void)solver::fit_model(steps, model, solver::measure_noise_floor(steps)),
               core::InputError);
  remove_db(db_path);
}

// The embedded station with seed `seed` and its LN200-class unit (noise, bias instability,
// 400 Hz) given a gyro output filter of 10 Hz (2nd-order Butterworth) and 5 ms of latency.
constexpr double kCutoffHz = 10.0, kLatencyS = 0.005;
core::StationConfig filtered_station(std::uint64_t seed, sim::ImuTruth& truth) {
  core::StationConfig station = sim::default_station();
  station.seed = seed;
  truth = sim::resolve_imu_truth(station.imus[0], station.seed, 0);
  truth.gyro_bandwidth_hz = kCutoffHz;
  truth.filter_order = 2;
  truth.latency_s = kLatencyS;
  station.imus[0].model.clear();
  station.imus[0].truth = sim::imu_truth_to_json(truth);
  return station;
}

// bandwidth determines no error-model term (its means are static poses): it is documented for
// `calstand analyze bandwidth`. Its LN200-class unit (noise, bias instability, 400 Hz) is given
// a gyro output filter of 10 Hz (2nd-order Butterworth) and 5 ms of latency; the analysis must
// find the cutoff within 10 % and the latency within one sample period (2.5 ms) on each axis.
TEST(LibraryBandwidth, RecoversTheOutputFilterCutoffAndLatency) {
  sim::ImuTruth truth;
  const core::StationConfig station = filtered_station(1, truth);
  const std::string db_path = fresh_db("bandwidth");
  const std::int64_t run_id = run_procedure(
      "bandwidth", {"frequencies_hz=[1,2,4,6,8,10,12,15]", "amplitude_deg=0.03", "cycles=20"},
      db_path, station);
  if (HasFailure()) return;
  store::Database db(db_path);
  const analysis::BandwidthAnalysis b = analysis::analyse_bandwidth(db, run_id, "");
  EXPECT_EQ(b.points.size(), 24u);
  const double period_s = 1.0 / truth.sample_rate_hz;
  for (std::size_t a = 0; a < 3; ++a) {
    ASSERT_TRUE(b.bandwidth_hz[a]) << "axis " << a;
    ASSERT_TRUE(b.delay_s[a]) << "axis " << a;
    EXPECT_NEAR(*b.bandwidth_hz[a], kCutoffHz, 0.1 * kCutoffHz) << "axis " << a;
    EXPECT_NEAR(*b.delay_s[a], kLatencyS, period_s) << "axis " << a;
    EXPECT_EQ(b.low_pass_order[a], 2) << "axis " << a;
    std::cout << "axis " << a << ": bandwidth " << *b.bandwidth_hz[a] << " Hz, delay "
              << *b.delay_s[a] * 1e3 << " ms\n";
  }
  // Well below the cutoff the gain is one.
  EXPECT_NEAR(b.points.front().gain, 1.0, 0.02);
  remove_db(db_path);
}

// The 95 % intervals of the bandwidth and the delay, over six station seeds (each its own noise
// and its own unit drawn from the sheet) with the same 10 Hz filter and 5 ms latency: each
// interval should hold the truth, so of the 18 per figure about one misses; three or more
// would be unlikely by chance (binomial, p < 0.06) and more than that a bias or too narrow an
// interval. The intervals must also say something (narrower than 10 % of the value), and the
// sigma they state must be the scatter the estimates show across the seeds (pooled over the
// axes, 15 degrees of freedom: the ratio lies within 0.65 .. 1.35 at 95 %), within a factor
// of 2.
TEST(LibraryBandwidth, IntervalsHoldTheTruthAndTheirSigmaIsTheScatterAcrossSeeds) {
  constexpr int kSeeds = 6;
  int bandwidth_misses = 0, delay_misses = 0;
  std::array<std::vector<double>, 3> bandwidths, delays;
  double bandwidth_variance = 0.0, delay_variance = 0.0;  // of the stated sigmas, summed
  for (int seed = 1; seed <= kSeeds; ++seed) {
    sim::ImuTruth truth;
    const core::StationConfig station = filtered_station(static_cast<std::uint64_t>(seed), truth);
    const std::string db_path = fresh_db("bandwidth-interval-" + std::to_string(seed));
    const std::int64_t run_id = run_procedure(
        "bandwidth", {"frequencies_hz=[1,2,4,6,8,10,12,15]", "amplitude_deg=0.03", "cycles=20"},
        db_path, station);
    if (HasFailure()) return;
    store::Database db(db_path);
    const analysis::BandwidthAnalysis b = analysis::analyse_bandwidth(db, run_id, "");
    EXPECT_DOUBLE_EQ(b.confidence, 0.95);
    for (const auto& p : b.points) {
      EXPECT_GT(p.gain_sigma, 0.0) << "seed " << seed << " step " << p.step;
      EXPECT_GT(p.phase_sigma_deg, 0.0) << "seed " << seed << " step " << p.step;
      EXPECT_EQ(p.segments, 10);  // 20 periods, two a segment
    }
    for (std::size_t a = 0; a < 3; ++a) {
      ASSERT_TRUE(b.bandwidth_hz[a] && b.bandwidth_interval_hz[a] && b.bandwidth_sigma_hz[a])
          << "seed " << seed << " axis " << a;
      ASSERT_TRUE(b.delay_s[a] && b.delay_interval_s[a] && b.delay_sigma_s[a])
          << "seed " << seed << " axis " << a;
      const auto& fc = *b.bandwidth_interval_hz[a];
      const auto& tau = *b.delay_interval_s[a];
      std::cout << "seed " << seed << " axis " << a << ": bandwidth " << *b.bandwidth_hz[a]
                << " Hz [" << fc[0] << ", " << fc[1] << "], delay " << *b.delay_s[a] * 1e3
                << " ms [" << tau[0] * 1e3 << ", " << tau[1] * 1e3 << "]\n";
      EXPECT_LE(fc[0], *b.bandwidth_hz[a]);
      EXPECT_GE(fc[1], *b.bandwidth_hz[a]);
      EXPECT_LE(tau[0], *b.delay_s[a]);
      EXPECT_GE(tau[1], *b.delay_s[a]);
      if (!(fc[0] <= kCutoffHz && kCutoffHz <= fc[1])) ++bandwidth_misses;
      if (!(tau[0] <= kLatencyS && kLatencyS <= tau[1])) ++delay_misses;
      EXPECT_LT(fc[1] - fc[0], 0.1 * kCutoffHz) << "seed " << seed << " axis " << a;
      EXPECT_LT(tau[1] - tau[0], 0.1 * kLatencyS) << "seed " << seed << " axis " << a;
      bandwidths[a].push_back(*b.bandwidth_hz[a]);
      delays[a].push_back(*b.delay_s[a]);
      bandwidth_variance += std::pow(*b.bandwidth_sigma_hz[a], 2);
      delay_variance += std::pow(*b.delay_sigma_s[a], 2);
    }
    remove_db(db_path);
  }
  EXPECT_LE(bandwidth_misses, 2);
  EXPECT_LE(delay_misses, 2);
  // Scatter about each axis's own mean across the seeds, pooled.
  const auto pooled_scatter = [](const std::array<std::vector<double>, 3>& values) {
    double ss = 0.0, dof = 0.0;
    for (const auto& v : values) {
      double mean = 0.0;
      for (const double x : v) mean += x;
      mean /= static_cast<double>(v.size());
      for (const double x : v) ss += (x - mean) * (x - mean);
      dof += static_cast<double>(v.size()) - 1.0;
    }
    return std::sqrt(ss / dof);
  };
  const double stated_bandwidth = std::sqrt(bandwidth_variance / (3.0 * kSeeds));
  const double stated_delay = std::sqrt(delay_variance / (3.0 * kSeeds));
  const double bandwidth_ratio = pooled_scatter(bandwidths) / stated_bandwidth;
  const double delay_ratio = pooled_scatter(delays) / stated_delay;
  std::cout << "scatter / stated sigma: bandwidth " << bandwidth_ratio << ", delay " << delay_ratio
            << "\n";
  EXPECT_GT(bandwidth_ratio, 0.5);
  EXPECT_LT(bandwidth_ratio, 2.0);
  EXPECT_GT(delay_ratio, 0.5);
  EXPECT_LT(delay_ratio, 2.0);
}

}  // namespace
}  // namespace calstand

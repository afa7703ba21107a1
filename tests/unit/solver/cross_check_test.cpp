// Each classical method (classical.hpp, thermal.hpp) cross-checked against the general fit
// (fit_model) on the SAME simulated step means (issue 4). Both are least squares of the same
// linear model, so on equal weights they must agree to rounding, not merely within noise:
// - fit_model weights each (step, channel) row by the noise floor of that channel's step mean;
//   every parameter here acts on one channel only, so the joint fit splits into independent
//   per-channel fits and the per-channel weight cancels as long as all steps have the same
//   length (same count, same sigma). The classical methods weight all positions equally.
// - Sigmas: fit_model without chi2 inflation propagates the noise floor; the classical methods
//   are given the same per-axis step-mean sigma, so the sigmas must agree too.
// The classical side gets its reference from the table geometry and the site (not from the
// Model), so the general fit's reference and regressor conventions are checked as well.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "sim/noise.hpp"
#include "sim_run.hpp"
#include "solver/classical.hpp"
#include "solver/fit.hpp"
#include "solver/thermal.hpp"

namespace calstand::solver {
namespace {

using testing::SimStep;
using testing::simulate_run;
using testing::white_noise_truth;

constexpr double kDegPerRad = 180.0 / M_PI;
// Agreement of two solutions of the same least-squares problem: relative to the larger of the
// value and its sigma (a value near zero is compared on the scale of its uncertainty).
constexpr double kValueRel = 1e-9;
constexpr double kSigmaRel = 1e-7;
constexpr double kSampleRateHz = 100.0;  // white_noise_truth()'s output rate

/// A unit with bias, scale and misalignment drawn per seed (LN200-class magnitudes).
sim::ImuTruth random_cross_check_unit(std::uint64_t seed, double gyro_noise_dps_rthz = 2e-3) {
  sim::NormalSource n(seed * 7919 + 3);
  sim::ImuTruth t = white_noise_truth(gyro_noise_dps_rthz);
  testing::draw_classical_errors(t, n);
  return t;
}

/// Step summaries of one simulated run with its noise floor.
struct Summaries {
  RunData data;
  std::vector<StepSummary> steps;
  NoiseFloor floor;
};

Summaries summarize(RunData data, const Model& model) {
  Summaries s;
  s.steps = summarize_steps(data, model);
  s.floor = measure_noise_floor(s.steps);
  s.data = std::move(data);
  return s;
}

SimStep position(double outer_deg, double inner_deg, double duration_s = 20.0) {
  SimStep s;
  s.outer_deg = outer_deg;
  s.inner_deg = inner_deg;
  s.duration_s = duration_s;
  return s;
}

const FittedParameter* find_parameter(const FitResult& fit, const std::string& name) {
  for (const auto& p : fit.parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

bool unidentifiable(const FitResult& fit, const std::string& name) {
  for (const auto& u : fit.unidentifiable) {
    if (u.name == name) return true;
  }
  return false;
}

/// Classical estimate vs the general fit's parameter of the same contract name.
void expect_agree(const FitResult& fit, const ClassicalEstimate& c, bool compare_sigma = true) {
  const FittedParameter* p = find_parameter(fit, c.name);
  ASSERT_NE(p, nullptr) << c.name << " not identified by the general fit";
  EXPECT_EQ(p->unit, c.unit) << c.name;
  EXPECT_NEAR(c.value, p->value, kValueRel * std::max(std::abs(p->value), p->sigma))
      << c.name << " classical " << c.value << " general " << p->value << " sigma " << p->sigma;
  if (compare_sigma) {
    EXPECT_NEAR(c.sigma, p->sigma, kSigmaRel * p->sigma) << c.name;
  }
}

void expect_agree(const FitResult& fit, const std::string& name, double value, double sigma) {
  const FittedParameter* p = find_parameter(fit, name);
  ASSERT_NE(p, nullptr) << name << " not identified by the general fit";
  EXPECT_NEAR(value, p->value, kValueRel * std::max(std::abs(p->value), p->sigma))
      << name << " classical " << value << " general " << p->value << " sigma " << p->sigma;
  EXPECT_NEAR(sigma, p->sigma, kSigmaRel * p->sigma) << name;
}

/// Accelerometer U (3xN) and A (4xN) for the matrix methods: measured step means, and the
/// reference f_B = C_BL (0, 0, g) from the geometry (independent of Model::reference).
void accel_matrices(const Summaries& s, const std::vector<SimStep>& steps, Eigen::Matrix3Xd& U,
                    Eigen::Matrix4Xd& A) {
  const auto n = static_cast<Eigen::Index>(steps.size());
  U.resize(3, n);
  A.resize(4, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const SimStep& st = steps[static_cast<std::size_t>(k)];
    const Eigen::Matrix3d C_LB = s.data.setup.geometry.body_to_level(st.outer_deg, st.inner_deg);
    U.col(k) = s.steps[static_cast<std::size_t>(k)].measured.tail<3>();
    A.col(k) << C_LB.transpose() * s.data.setup.site.specific_force_level(), 1.0;
  }
}

FitOptions no_inflation(SensorRows rows) {
  FitOptions o;
  o.rows = rows;
  o.inflate_sigma_by_chi2 = false;  // the classical sigmas propagate the given sigma only
  return o;
}

const char* kAccelMatrixModel = "accel_bias,accel_scale,accel_misalignment";

// --- Six-position ---------------------------------------------------------------------------

TEST(CrossCheck, SixPositionMatchesGeneralFit) {
  const std::vector<SimStep> steps = testing::six_positions();
  const Model model = Model::parse(kAccelMatrixModel);
  const Summaries s = summarize(simulate_run(random_cross_check_unit(1), steps, 11), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kAccel));
  ASSERT_TRUE(fit.unidentifiable.empty()) << fit.unidentifiable.front().name;

  Eigen::Matrix3Xd U;
  Eigen::Matrix4Xd A;
  accel_matrices(s, steps, U, A);
  MatrixFitOptions options;
  options.measurement_sigma = s.floor.step_sigma(s.steps.front().count).tail<3>();
  const MatrixCalibration six =
      six_position(Eigen::Matrix<double, 3, 6>(U), Eigen::Matrix<double, 4, 6>(A), options);
  const auto named = named_parameters(six, ClassicalSensor::kAccel);
  ASSERT_EQ(named.size(), 12u);
  for (const auto& c : named) expect_agree(fit, c);
}

// With no redundancy (6 positions, 4 unknowns per axis) and no given sigma the classical sigmas
// come from the residual scatter, the general fit's from the noise floor: those differ by
// design, but each is proportional to its noise measure, so their ratio is the same for every
// parameter of one axis.
TEST(CrossCheck, SixPositionResidualScatterSigmasAreProportional) {
  const std::vector<SimStep> steps = testing::six_positions();
  const Model model = Model::parse(kAccelMatrixModel);
  const Summaries s = summarize(simulate_run(random_cross_check_unit(2), steps, 12), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kAccel));
  Eigen::Matrix3Xd U;
  Eigen::Matrix4Xd A;
  accel_matrices(s, steps, U, A);
  const MatrixCalibration six =
      six_position(Eigen::Matrix<double, 3, 6>(U), Eigen::Matrix<double, 4, 6>(A));
  ASSERT_EQ(six.sigma_source, SigmaSource::kResidualScatter);
  const Eigen::Vector3d floor_sigma = s.floor.step_sigma(s.steps.front().count).tail<3>();
  for (const auto& c : named_parameters(six, ClassicalSensor::kAccel)) {
    expect_agree(fit, c, /*compare_sigma=*/false);
    const FittedParameter* p = find_parameter(fit, c.name);
    ASSERT_NE(p, nullptr);
    const std::string axis_letter = c.name.substr(c.name.find('.') + 1, 1);
    const int axis = axis_letter[0] - 'x';
    const double ratio = six.measurement_sigma[axis] / floor_sigma[axis];
    EXPECT_NEAR(c.sigma, ratio * p->sigma, kSigmaRel * ratio * p->sigma) << c.name;
  }
}

// --- Multi-position -------------------------------------------------------------------------

TEST(CrossCheck, MultiPositionMatchesGeneralFit) {
  // Ten attitudes, most of them oblique: every regressor takes many values.
  const std::vector<SimStep> steps = {position(0, 0),   position(180, 0),   position(90, 0),
                                      position(-90, 0), position(90, 90),   position(-90, 90),
                                      position(45, 30), position(-60, 120), position(135, -45),
                                      position(30, 200)};
  const Model model = Model::parse(kAccelMatrixModel);
  const Summaries s = summarize(simulate_run(random_cross_check_unit(3), steps, 13), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kAccel));
  ASSERT_TRUE(fit.unidentifiable.empty()) << fit.unidentifiable.front().name;
  Eigen::Matrix3Xd U;
  Eigen::Matrix4Xd A;
  accel_matrices(s, steps, U, A);
  MatrixFitOptions options;
  options.measurement_sigma = s.floor.step_sigma(s.steps.front().count).tail<3>();
  const MatrixCalibration multi = multi_position(U, A, options);
  for (const auto& c : named_parameters(multi, ClassicalSensor::kAccel)) expect_agree(fit, c);
}

// --- Twelve-position ------------------------------------------------------------------------

TEST(CrossCheck, TwelvePositionMatchesGeneralFitForBothTriads) {
  std::vector<SimStep> steps;
  for (const TableAngles& a : twelve_position_table_angles()) {
    steps.push_back(position(a.outer_deg, a.inner_deg));
  }
  // A quiet gyro: on the Earth rate alone the gyro scale sigma is step sigma / W (W = 4.2e-3
  // deg/s); the general fit refuses sigmas beyond 1e4 ppm as "barely excited".
  const sim::ImuTruth truth = random_cross_check_unit(4, /*gyro_noise_dps_rthz=*/2e-5);
  const Model model = Model::parse(
      "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_"
      "misalignment");
  const Summaries s = summarize(simulate_run(truth, steps, 14), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kBoth));
  ASSERT_TRUE(fit.unidentifiable.empty())
      << fit.unidentifiable.front().name << ": " << fit.unidentifiable.front().reason;

  const std::array<Eigen::Matrix3d, 12> documented = twelve_position_attitudes(180.0);
  std::vector<StaticPosition> positions;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    StaticPosition p;
    p.gyro_dps = s.steps[k].measured.head<3>();
    p.accel_mps2 = s.steps[k].measured.tail<3>();
    p.C_LB = s.data.setup.geometry.body_to_level(steps[k].outer_deg, steps[k].inner_deg);
    // twelve_position_attitudes(180) is documented to equal the table angles' attitudes.
    EXPECT_LT((p.C_LB - documented[k]).norm(), 1e-12) << "position " << k;
    positions.push_back(p);
  }
  const Vector6d sigma = s.floor.step_sigma(s.steps.front().count);
  TwelvePositionOptions options;
  options.gyro.measurement_sigma = sigma.head<3>();
  options.accel.measurement_sigma = sigma.tail<3>();
  const core::Site& site = s.data.setup.site;
  const TwelvePositionResult twelve = twelve_position(
      positions, site.gravity(), site.earth_rate_level_radps() * kDegPerRad, options);
  for (const auto& c : named_parameters(twelve.gyro, ClassicalSensor::kGyro)) expect_agree(fit, c);
  for (const auto& c : named_parameters(twelve.accel, ClassicalSensor::kAccel))
    expect_agree(fit, c);
}

// --- Two-position ---------------------------------------------------------------------------

// z up / z down, level (tilt 0) and with the z axis tilted by 10 deg about the outer axis in
// both positions. Only z is excited along its own axis: the y (and, level, x) scale factors are
// unidentifiable in the general fit and have no classical counterpart.
TEST(CrossCheck, TwoPositionMatchesGeneralFitOnTheExcitedAxis) {
  for (double tilt_deg : {0.0, 10.0}) {
    SCOPED_TRACE(::testing::Message() << "tilt " << tilt_deg << " deg");
    const std::vector<SimStep> steps = {position(tilt_deg, 0), position(180.0 + tilt_deg, 0)};
    const Model model = Model::parse("accel_bias,accel_scale");
    const Summaries s = summarize(simulate_run(random_cross_check_unit(5), steps, 15), model);
    const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kAccel));
    // The tilt turns z about the outer axis (North) towards body x: y is never excited.
    EXPECT_TRUE(unidentifiable(fit, "accel_scale.y"));
    if (tilt_deg == 0.0) {
      EXPECT_TRUE(unidentifiable(fit, "accel_scale.x"));
    }

    const double sigma_z = s.floor.step_sigma(s.steps.front().count)[kAz];
    const TwoPositionResult two =
        two_position(s.steps[0].measured[kAz], s.steps[1].measured[kAz],
                     s.data.setup.site.gravity(), tilt_deg / kDegPerRad, sigma_z);
    expect_agree(fit, "accel_bias.z", two.bias, two.bias_sigma);
    expect_agree(fit, "accel_scale.z", two.scale_ppm, two.scale_sigma_ppm);
  }
}

// --- CW/CCW rate test -----------------------------------------------------------------------

/// Rate steps about the vertical inner axis (body z up) at +-rate for each rate; 36 s is a
/// whole number of turns at 20 and 100 deg/s, so the horizontal Earth rate (and with it the
/// misalignment coupling into z) averages out, as the CW/CCW method assumes.
std::vector<SimStep> vertical_rate_steps(const std::vector<double>& rates_dps) {
  std::vector<SimStep> out;
  for (double r : rates_dps) {
    for (double sign : {1.0, -1.0}) {
      SimStep st;
      st.inner_rate_dps = sign * r;
      st.duration_s = 36.0;
      out.push_back(st);
    }
  }
  return out;
}

double vertical_earth_rate_at_dps(const core::Site& site) {
  return site.earth_rate_level_radps().z() * kDegPerRad;
}

TEST(CrossCheck, RateTestCwCcwMatchesGeneralFit) {
  const std::vector<SimStep> steps = vertical_rate_steps({20.0});
  const Model model = Model::parse("gyro_bias,gyro_scale,earth_rate");
  // The truth keeps its misalignment: z must still come out exact (whole turns).
  const Summaries s = summarize(simulate_run(random_cross_check_unit(6), steps, 16), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kGyro));
  // The horizontal axes see no mean rate over whole turns.
  EXPECT_TRUE(unidentifiable(fit, "gyro_scale.x"));
  EXPECT_TRUE(unidentifiable(fit, "gyro_scale.y"));

  const double w_z = vertical_earth_rate_at_dps(s.data.setup.site);
  const double sigma_z = s.floor.step_sigma(s.steps.front().count)[kGz];
  const double rate = steps[0].inner_rate_dps;
  const RateTestResult by_rates = rate_test_cw_ccw_rates(
      s.steps[0].measured[kGz], s.steps[1].measured[kGz], rate, w_z, sigma_z);
  expect_agree(fit, "gyro_bias.z", by_rates.bias_dps, by_rates.bias_sigma_dps);
  expect_agree(fit, "gyro_scale.z", by_rates.scale_ppm, by_rates.scale_sigma_ppm);

  // The integrated-angle form on the same samples: angle = mean rate * n dt over n samples.
  const double t = static_cast<double>(s.steps[0].count) / kSampleRateHz;
  ASSERT_GT(t, 0.0);
  const RateTestResult by_angle = rate_test_cw_ccw(
      s.steps[0].measured[kGz] * t, s.steps[1].measured[kGz] * t, rate * t, t, w_z, sigma_z * t);
  expect_agree(fit, "gyro_bias.z", by_angle.bias_dps, by_angle.bias_sigma_dps);
  expect_agree(fit, "gyro_scale.z", by_angle.scale_ppm, by_angle.scale_sigma_ppm);
}

TEST(CrossCheck, RateStepsLineMatchesGeneralFit) {
  const std::vector<SimStep> steps = vertical_rate_steps({20.0, 100.0});
  const Model model = Model::parse("gyro_bias,gyro_scale,earth_rate");
  const Summaries s = summarize(simulate_run(random_cross_check_unit(7), steps, 17), model);
  const FitResult fit = fit_model(s.steps, model, s.floor, no_inflation(SensorRows::kGyro));
  std::vector<RateStep> rate_steps_in;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    rate_steps_in.push_back({steps[k].inner_rate_dps, s.steps[k].measured[kGz]});
  }
  const double sigma_z = s.floor.step_sigma(s.steps.front().count)[kGz];
  const RateTestResult line =
      rate_steps(rate_steps_in, vertical_earth_rate_at_dps(s.data.setup.site), sigma_z);
  expect_agree(fit, "gyro_bias.z", line.bias_dps, line.bias_sigma_dps);
  expect_agree(fit, "gyro_scale.z", line.scale_ppm, line.scale_sigma_ppm);
}

// --- Thermal --------------------------------------------------------------------------------

// Six positions on each of four plateaus. Per plateau, the six-position design makes bias,
// scale and misalignment columns orthogonal, so per-plateau fits followed by a weighted
// polynomial (thermal_calibration) solve exactly the normal equations of one fit with the
// temperature terms: the two must agree to rounding.
TEST(CrossCheck, ThermalPerPlateauMatchesSingleFitWithTemperatureTerms) {
  sim::ImuTruth truth = random_cross_check_unit(8, /*gyro_noise_dps_rthz=*/2e-5);
  truth.gyro_temp_bias = {Eigen::Vector3d(4e-5, -2e-5, 1e-5), Eigen::Vector3d(5e-7, 3e-7, -4e-7)};
  truth.accel_temp_bias = {Eigen::Vector3d(1e-4, -5e-5, 2e-5), Eigen::Vector3d(2e-6, -1e-6, 1e-6)};
  truth.accel_temp_scale = Eigen::Vector3d(2.0, -1.5, 1.0);
  const std::vector<double> temperatures = {-20.0, 5.0, 30.0, 60.0};
  std::vector<SimStep> steps;
  for (double temp : temperatures) {
    for (const SimStep& st : testing::six_positions(temp)) steps.push_back(st);
  }
  const RunData data = simulate_run(truth, steps, 18);
  const double t_ref = data.setup.temperature_ref_c;
  ThermalOptions thermal;
  thermal.temperature_ref_c = t_ref;

  struct Case {
    SensorRows rows;
    const char* plateau_model;
    const char* single_model;
  };
  for (const Case& c :
       {Case{SensorRows::kAccel, kAccelMatrixModel,
             "accel_bias,accel_scale,accel_misalignment,accel_temp_bias:2,"
             "accel_temp_scale"},
        Case{SensorRows::kGyro, "gyro_bias,earth_rate", "gyro_bias,gyro_temp_bias:2,earth_rate"}}) {
    SCOPED_TRACE(c.plateau_model);
    // One noise floor for both sides: the weights must be the same.
    const Model single_model = Model::parse(c.single_model);
    const std::vector<StepSummary> all = summarize_steps(data, single_model);
    const NoiseFloor floor = measure_noise_floor(all);
    const FitResult single = fit_model(all, single_model, floor, no_inflation(c.rows));
    ASSERT_TRUE(single.unidentifiable.empty()) << single.unidentifiable.front().name;

    const Model plateau_model = Model::parse(c.plateau_model);
    const std::vector<StepSummary> per_step = summarize_steps(data, plateau_model);
    std::vector<ThermalPlateau> biases;
    std::vector<ThermalPlateau> scales;
    for (std::size_t p = 0; p < temperatures.size(); ++p) {
      const std::vector<StepSummary> plateau(per_step.begin() + static_cast<long>(6 * p),
                                             per_step.begin() + static_cast<long>(6 * (p + 1)));
      const FitResult fit = fit_model(plateau, plateau_model, floor, no_inflation(c.rows));
      ThermalPlateau b{plateau[0].signals[0], {}};
      ThermalPlateau sc{plateau[0].signals[0], {}};
      for (const auto& q : fit.parameters) {
        const ClassicalEstimate e{q.name, q.value, q.sigma, q.unit};
        if (q.name.find("_bias.") != std::string::npos) b.parameters.push_back(e);
        if (q.name.find("_scale.") != std::string::npos) sc.parameters.push_back(e);
      }
      biases.push_back(b);
      scales.push_back(sc);
    }
    std::vector<ClassicalEstimate> thermal_estimates = thermal_calibration(biases, 2, thermal);
    if (!scales.front().parameters.empty()) {
      for (const auto& e : thermal_calibration(scales, 1, thermal)) thermal_estimates.push_back(e);
    }
    ASSERT_EQ(thermal_estimates.size(), c.rows == SensorRows::kAccel ? 15u : 9u);
    for (const ClassicalEstimate& e : thermal_estimates) {
      // Units: the fit's catalogue writes temp_bias units with a literal "^k"
      // ("deg/s/degC^k"), thermal_calibration with the power ("deg/s/degC^2"): compare values.
      const FittedParameter* p = find_parameter(single, e.name);
      ASSERT_NE(p, nullptr) << e.name;
      EXPECT_NEAR(e.value, p->value, kValueRel * std::max(std::abs(p->value), p->sigma))
          << e.name << " thermal " << e.value << " single fit " << p->value;
      EXPECT_NEAR(e.sigma, p->sigma, kSigmaRel * p->sigma) << e.name;
    }
  }
}

}  // namespace
}  // namespace calstand::solver

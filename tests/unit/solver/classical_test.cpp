// Classical calibration methods against their closed forms and against simulated ground truth:
// exact means from sim::imu_inputs() + sim::deterministic_errors() (noiseless: recovery to
// rounding), then seeded white noise on the means (recovery within 3 sigma, sigmas honest).

#include "solver/classical.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "sim/imu_sim.hpp"
#include "sim/imu_truth.hpp"
#include "sim/noise.hpp"

namespace calstand::solver {
namespace {

core::Site test_site() {
  core::Site site;
  site.latitude_deg = 30.53;
  site.height_m = 20.0;
  site.gravity_mps2 = 9.7936;
  return site;
}

double earth_rate_dps() { return core::kEarthRateRadPerS * core::kRadToDeg; }
double vertical_earth_rate_dps() {
  return earth_rate_dps() * std::sin(test_site().latitude_deg * core::kDegToRad);
}

// A device with every parameter the matrix methods estimate, of realistic size.
sim::ImuTruth full_truth() {
  sim::ImuTruth t;
  t.accel_bias = {0.021, -0.015, 0.034};
  t.accel_scale = {310.0, -220.0, 145.0};
  t.accel_misalignment << 0.0, 1.2e-3, -0.7e-3,  //
      -0.4e-3, 0.0, 0.9e-3,                      //
      0.6e-3, -1.1e-3, 0.0;
  t.gyro_bias = {0.012, -0.006, 0.009};
  t.gyro_scale = {520.0, -310.0, 205.0};
  t.gyro_misalignment << 0.0, -0.8e-3, 0.5e-3,  //
      1.3e-3, 0.0, -0.6e-3,                     //
      -0.9e-3, 0.4e-3, 0.0;
  return t;
}

struct Means {
  Eigen::Vector3d gyro_dps;
  Eigen::Vector3d accel_mps2;
  sim::ImuInputs reference;  // true rate and force in B
};

// Noiseless means at a table state: the reference plus the deterministic errors.
Means exact_means(const sim::ImuTruth& truth, const sim::TableKinematics& table,
                  const Eigen::Vector2d& tilt = Eigen::Vector2d::Zero(), double temp_c = 25.0) {
  const sim::ImuInputs in =
      sim::imu_inputs(truth, core::TableGeometry{}, test_site(), tilt, table, temp_c);
  const auto [gyro_err, accel_err] = sim::deterministic_errors(truth, in);
  return {in.rate_dps + gyro_err, in.force_mps2 + accel_err, in};
}

Means static_means(const sim::ImuTruth& truth, double outer_deg, double inner_deg) {
  sim::TableKinematics k;
  k.outer_deg = outer_deg;
  k.inner_deg = inner_deg;
  return exact_means(truth, k);
}

// +x, -x, +y, -y, +z, -z up on the default table (outer North, inner Up at zero).
const std::vector<std::pair<double, double>>& six_angles() {
  static const std::vector<std::pair<double, double>> a{{-90.0, 0.0},  {90.0, 0.0}, {-90.0, -90.0},
                                                        {90.0, -90.0}, {0.0, 0.0},  {180.0, 0.0}};
  return a;
}

struct Design {
  Eigen::Matrix<double, 3, 6> U;
  Eigen::Matrix<double, 4, 6> A;
};

// Six positions of one sensor: measured means and [reference; 1].
Design six_design(const sim::ImuTruth& truth, bool gyro) {
  Design d;
  for (int k = 0; k < 6; ++k) {
    const auto [outer, inner] = six_angles()[static_cast<std::size_t>(k)];
    const Means m = static_means(truth, outer, inner);
    d.U.col(k) = gyro ? m.gyro_dps : m.accel_mps2;
    d.A.col(k) << (gyro ? m.reference.rate_dps : m.reference.force_mps2), 1.0;
  }
  return d;
}

void expect_matches_truth(const MatrixCalibration& fit, const Eigen::Vector3d& bias,
                          const Eigen::Vector3d& scale_ppm, const Eigen::Matrix3d& mis,
                          double bias_tol, double scale_tol_ppm, double mis_tol) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(fit.bias(i), bias(i), bias_tol) << "bias axis " << i;
    EXPECT_NEAR(fit.scale_ppm(i), scale_ppm(i), scale_tol_ppm) << "scale axis " << i;
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(fit.misalignment_rad(i, j), mis(i, j), mis_tol) << "mis " << i << j;
    }
  }
}

// |estimate - truth| / sigma for every parameter of a matrix fit.
std::vector<double> normalised_errors(const MatrixCalibration& fit, const Eigen::Vector3d& bias,
                                      const Eigen::Vector3d& scale_ppm,
                                      const Eigen::Matrix3d& mis) {
  std::vector<double> z;
  for (int i = 0; i < 3; ++i) {
    z.push_back((fit.bias(i) - bias(i)) / fit.bias_sigma(i));
    z.push_back((fit.scale_ppm(i) - scale_ppm(i)) / fit.scale_sigma_ppm(i));
    for (int j = 0; j < 3; ++j) {
      if (i != j)
        z.push_back((fit.misalignment_rad(i, j) - mis(i, j)) / fit.misalignment_sigma_rad(i, j));
    }
  }
  return z;
}

template <typename Matrix>
void add_noise(Matrix& U, double sigma, sim::NormalSource& normal) {
  for (Eigen::Index c = 0; c < U.cols(); ++c) {
    for (Eigen::Index r = 0; r < U.rows(); ++r) U(r, c) += sigma * normal.next();
  }
}

// ------------------------------------------------------------------------------------------
// Two-position

TEST(ClassicalTwoPosition, ClosedFormWithTilt) {
  const double g = 9.7936;
  const double b = 0.0234;
  const double s = 412e-6;
  const double tilt = 0.02;
  const double up = b + (1.0 + s) * g * std::cos(tilt);
  const double down = b - (1.0 + s) * g * std::cos(tilt);
  const TwoPositionResult r = two_position(up, down, g, tilt);
  EXPECT_NEAR(r.bias, b, 1e-12);
  EXPECT_NEAR(r.scale_ppm, 412.0, 1e-8);
  // Ignoring the tilt reads the cosine loss as scale: 1e6 (cos(0.02) - 1) = -200 ppm.
  const TwoPositionResult untilted = two_position(up, down, g);
  EXPECT_NEAR(untilted.scale_ppm - r.scale_ppm, 1e6 * (std::cos(tilt) - 1.0) * (1.0 + s), 1e-6);
  EXPECT_LT(untilted.scale_ppm, 250.0);
  EXPECT_EQ(r.bias_sigma, 0.0);  // no redundancy, no sigma given
}

TEST(ClassicalTwoPosition, RecoversSimulatedAccelOnTiltedTable) {
  sim::ImuTruth truth = full_truth();
  truth.accel_misalignment.setZero();         // a tilted axis would see x/y gravity through it
  const Eigen::Vector2d tilt(0.003, -0.004);  // |tilt| = 5 mrad
  sim::TableKinematics up;
  sim::TableKinematics down;
  down.outer_deg = 180.0;
  const Means m_up = exact_means(truth, up, tilt);
  const Means m_down = exact_means(truth, down, tilt);
  const TwoPositionResult r =
      two_position(m_up.accel_mps2.z(), m_down.accel_mps2.z(), 9.7936, tilt.norm(), 1e-4);
  EXPECT_NEAR(r.bias, truth.accel_bias.z(), 1e-12);
  EXPECT_NEAR(r.scale_ppm, truth.accel_scale.z(), 1e-7);
  EXPECT_NEAR(r.bias_sigma, 1e-4 / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(r.scale_sigma_ppm, 1e6 * 1e-4 / (std::sqrt(2.0) * 9.7936 * std::cos(tilt.norm())),
              1e-9);
}

TEST(ClassicalTwoPosition, GyroOnEarthRate) {
  sim::ImuTruth truth = full_truth();
  truth.gyro_misalignment.setZero();  // z would see the North component through M_zy
  const Means up = static_means(truth, 0.0, 0.0);
  const Means down = static_means(truth, 180.0, 0.0);
  const TwoPositionResult r =
      two_position_gyro(up.gyro_dps.z(), down.gyro_dps.z(), vertical_earth_rate_dps(), 2e-4);
  EXPECT_NEAR(r.bias, truth.gyro_bias.z(), 1e-14);
  EXPECT_NEAR(r.scale_ppm, truth.gyro_scale.z(), 1e-6);
  // Weak observability: 2e-4 deg/s on each mean is ~4 % of scale on a 0.0037 deg/s reference.
  EXPECT_GT(r.scale_sigma_ppm, 3e4);
}

TEST(ClassicalTwoPosition, RefusesBadInput) {
  EXPECT_THROW(two_position(9.8, -9.8, 9.8, core::kPi / 2.0), core::InputError);
  EXPECT_THROW(two_position(9.8, -9.8, 0.0), core::InputError);
  EXPECT_THROW(two_position(NAN, -9.8, 9.8), core::InputError);
  EXPECT_THROW(two_position(9.8, -9.8, 9.8, 0.0, -1.0), core::InputError);
  EXPECT_THROW(two_position_gyro(0.01, 0.0, 0.0), core::InputError);
}

// ------------------------------------------------------------------------------------------
// Six-position and multi-position

TEST(ClassicalSixPosition, DesignIsTheSeedMatrix) {
  const Eigen::Matrix<double, 4, 6> A = six_position_design(9.8);
  Eigen::Matrix<double, 4, 6> expected;
  expected << 9.8, -9.8, 0, 0, 0, 0,  //
      0, 0, 9.8, -9.8, 0, 0,          //
      0, 0, 0, 0, 9.8, -9.8,          //
      1, 1, 1, 1, 1, 1;
  EXPECT_EQ(A, expected);
}

TEST(ClassicalSixPosition, AccelMatchesClosedForm) {
  // With the ideal design, A A^T = diag(2g^2, 2g^2, 2g^2, 6): b is the mean of all six
  // positions and column j of I+S+Mis is (u(+j) - u(-j)) / 2g.
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, false);
  const double g = 9.7936;
  const MatrixCalibration fit = six_position(d.U, six_position_design(g));
  const Eigen::Vector3d mean = d.U.rowwise().mean();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(fit.bias(i), mean(i), 1e-14);
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(fit.M(i, j), (d.U(i, 2 * j) - d.U(i, 2 * j + 1)) / (2.0 * g), 1e-14);
    }
  }
  EXPECT_NEAR(fit.condition_number, 1.0, 1e-9);
}

TEST(ClassicalSixPosition, AccelRecoversTruthNoiseless) {
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, false);
  const MatrixCalibration fit = six_position(d.U, d.A);
  expect_matches_truth(fit, truth.accel_bias, truth.accel_scale, truth.accel_misalignment, 1e-12,
                       1e-7, 1e-12);
  EXPECT_LT(fit.residuals.cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(fit.dof, 2);
  EXPECT_EQ(fit.sigma_source, SigmaSource::kResidualScatter);
}

TEST(ClassicalSixPosition, GyroOnEarthRateRecoversTruthButWeakly) {
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, true);
  MatrixFitOptions options;
  options.measurement_sigma = Eigen::Vector3d::Constant(1e-4);  // deg/s on each mean
  const MatrixCalibration fit = six_position(d.U, d.A, options);
  // Noiseless, the linear model holds exactly even on a 0.004 deg/s reference.
  expect_matches_truth(fit, truth.gyro_bias, truth.gyro_scale, truth.gyro_misalignment, 1e-14, 1e-6,
                       1e-12);
  // ...but the sigmas show what noise would do: a useful bias, a useless scale.
  EXPECT_LT(fit.bias_sigma.maxCoeff(), 1e-4);
  EXPECT_GT(fit.scale_sigma_ppm.minCoeff(), 1e4);
}

TEST(ClassicalSixPosition, EqualsMultiPositionOnSamePositions) {
  const sim::ImuTruth truth = full_truth();
  Design d = six_design(truth, false);
  sim::NormalSource normal(42);
  add_noise(d.U, 2e-4, normal);
  const MatrixCalibration six = six_position(d.U, d.A);
  const MatrixCalibration multi = multi_position(d.U, d.A);
  EXPECT_LT((six.M - multi.M).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT((six.residuals - multi.residuals).cwiseAbs().maxCoeff(), 1e-13);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(six.bias_sigma(i), multi.bias_sigma(i), 1e-12 * six.bias_sigma(i));
    EXPECT_NEAR(six.scale_sigma_ppm(i), multi.scale_sigma_ppm(i), 1e-9 * six.scale_sigma_ppm(i));
  }
  EXPECT_NEAR(six.condition_number, multi.condition_number, 1e-9);
  EXPECT_GT(six.residual_rms.minCoeff(), 0.0);  // the noise is seen
}

TEST(ClassicalSixPosition, NoisyWithinThreeSigma) {
  const sim::ImuTruth truth = full_truth();
  Design d = six_design(truth, false);
  sim::NormalSource normal(7);
  add_noise(d.U, 1e-4, normal);
  MatrixFitOptions options;
  options.measurement_sigma = Eigen::Vector3d::Constant(1e-4);
  const MatrixCalibration fit = six_position(d.U, d.A, options);
  for (double z :
       normalised_errors(fit, truth.accel_bias, truth.accel_scale, truth.accel_misalignment)) {
    EXPECT_LT(std::abs(z), 3.0);
  }
  EXPECT_EQ(fit.sigma_source, SigmaSource::kGiven);
}

TEST(ClassicalMultiPosition, SigmasAreHonestOverSeeds) {
  // Given-sigma fits over many seeds: the normalised errors must have unit RMS (a sigma formula
  // off by sqrt(2), or a wrong (A A^T)^-1 element, moves it far outside the band).
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, false);
  MatrixFitOptions options;
  options.measurement_sigma = Eigen::Vector3d::Constant(3e-4);
  // Per kind (bias, scale, misalignment), so one wrong sigma formula cannot hide in the mix.
  std::array<double, 3> sum_sq{};
  std::array<int, 3> count{};
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    Eigen::Matrix3Xd U = d.U;
    sim::NormalSource normal(seed);
    add_noise(U, 3e-4, normal);
    const MatrixCalibration fit = multi_position(U, d.A, options);
    const std::vector<double> z =
        normalised_errors(fit, truth.accel_bias, truth.accel_scale, truth.accel_misalignment);
    for (std::size_t k = 0; k < z.size(); ++k) {
      const std::size_t kind = k % 4 == 0 ? 0 : (k % 4 == 1 ? 1 : 2);  // order per axis: b s m m
      sum_sq[kind] += z[k] * z[k];
      ++count[kind];
    }
  }
  for (std::size_t kind = 0; kind < 3; ++kind) {
    const double rms = std::sqrt(sum_sq[kind] / count[kind]);
    EXPECT_GT(rms, 0.9) << "kind " << kind;
    EXPECT_LT(rms, 1.1) << "kind " << kind;
  }
}

TEST(ClassicalMultiPosition, ResidualScatterSigmaOnMorePositions) {
  // Eighteen positions (the six, three times) leave 14 dof for the scatter estimate.
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, false);
  Eigen::Matrix3Xd U(3, 18);
  Eigen::Matrix4Xd A(4, 18);
  for (int rep = 0; rep < 3; ++rep) {
    U.middleCols(6 * rep, 6) = d.U;
    A.middleCols(6 * rep, 6) = d.A;
  }
  sim::NormalSource normal(2024);
  add_noise(U, 1e-4, normal);
  const MatrixCalibration fit = multi_position(U, A);
  EXPECT_EQ(fit.dof, 14);
  EXPECT_EQ(fit.sigma_source, SigmaSource::kResidualScatter);
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(fit.measurement_sigma(i), 0.5e-4);
    EXPECT_LT(fit.measurement_sigma(i), 1.6e-4);
  }
  for (double z :
       normalised_errors(fit, truth.accel_bias, truth.accel_scale, truth.accel_misalignment)) {
    EXPECT_LT(std::abs(z), 3.5);  // t-distributed with 14 dof
  }
}

TEST(ClassicalMultiPosition, RefusesTooFewPositions) {
  const Design d = six_design(full_truth(), false);
  try {
    multi_position(d.U.leftCols(3), d.A.leftCols(3));
    FAIL() << "three positions accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "multi_position");
    EXPECT_NE(std::string(e.what()).find("3 positions given, need at least 4"), std::string::npos)
        << e.what();
  }
}

TEST(ClassicalMultiPosition, RefusesDegenerateGeometry) {
  // Only z up and z down, three times over: x and y references are zero in every position.
  const Design d = six_design(full_truth(), false);
  Eigen::Matrix3Xd U(3, 6);
  Eigen::Matrix4Xd A(4, 6);
  for (int k = 0; k < 6; ++k) {
    U.col(k) = d.U.col(4 + k % 2);
    A.col(k) = d.A.col(4 + k % 2);
  }
  try {
    multi_position(U, A);
    FAIL() << "degenerate geometry accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("do not determine M"), std::string::npos) << e.what();
  }
  // The x axis at the same angle to gravity in every position (say 60 deg from vertical, as
  // on a cone): its reference is a constant the bias column cannot be told from.
  Eigen::Matrix4Xd B(4, 6);
  B << 4.9, 4.9, 4.9, 4.9, 4.9, 4.9,  //
      8.5, -8.5, 0, 0, 6.0, -6.0,     //
      0, 0, 8.5, -8.5, 6.0, 6.0,      //
      1, 1, 1, 1, 1, 1;
  Eigen::Matrix<double, 3, 6> U6 = d.U;
  try {
    multi_position(U6, B);
    FAIL() << "collinear geometry accepted";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ref_x"), std::string::npos) << what;
    EXPECT_NE(what.find("bias"), std::string::npos) << what;
  }
  EXPECT_THROW(six_position(U6, Eigen::Matrix<double, 4, 6>(B)), core::InputError);
}

TEST(ClassicalMultiPosition, RefusesMismatchedOrNonFinite) {
  const Design d = six_design(full_truth(), false);
  EXPECT_THROW(multi_position(d.U.leftCols(5), d.A), core::InputError);
  Eigen::Matrix3Xd U = d.U;
  U(1, 2) = NAN;
  EXPECT_THROW(multi_position(U, d.A), core::InputError);
}

TEST(ClassicalMultiPosition, NamedParametersFollowTheContract) {
  const sim::ImuTruth truth = full_truth();
  const Design d = six_design(truth, false);
  const std::vector<ClassicalEstimate> named =
      named_parameters(multi_position(d.U, d.A), ClassicalSensor::kAccel);
  ASSERT_EQ(named.size(), 12u);
  EXPECT_EQ(named[0].name, "accel_bias.x");
  EXPECT_EQ(named[0].unit, "m/s^2");
  EXPECT_EQ(named[4].name, "accel_scale.y");
  EXPECT_EQ(named[4].unit, "ppm");
  EXPECT_NEAR(named[4].value, truth.accel_scale.y(), 1e-7);
  EXPECT_EQ(named[7].name, "accel_misalignment.xz");
  EXPECT_NEAR(named[7].value, truth.accel_misalignment(0, 2), 1e-12);
  EXPECT_EQ(named[11].name, "accel_misalignment.zy");
  EXPECT_NEAR(named[11].value, truth.accel_misalignment(2, 1), 1e-12);
  const auto gyro = named_parameters(multi_position(d.U, d.A), ClassicalSensor::kGyro);
  EXPECT_EQ(gyro[1].name, "gyro_bias.y");
  EXPECT_EQ(gyro[1].unit, "deg/s");
}

// ------------------------------------------------------------------------------------------
// Twelve-position

std::vector<StaticPosition> twelve_positions(const sim::ImuTruth& truth) {
  std::vector<StaticPosition> out;
  const core::TableGeometry geometry;
  for (const TableAngles& a : twelve_position_table_angles()) {
    const Means m = static_means(truth, a.outer_deg, a.inner_deg);
    out.push_back({m.gyro_dps, m.accel_mps2, geometry.body_to_level(a.outer_deg, a.inner_deg)});
  }
  return out;
}

Eigen::Vector3d earth_rate_level_dps() {
  return test_site().earth_rate_level_radps() * core::kRadToDeg;
}

TEST(ClassicalTwelvePosition, ArrangementIsEachAxisUpAndDownAtTwoHeadings) {
  const core::TableGeometry geometry;
  const auto angles = twelve_position_table_angles();
  for (int k = 0; k < 12; ++k) {
    const Eigen::Matrix3d C_LB =
        geometry.body_to_level(angles[static_cast<std::size_t>(k)].outer_deg,
                               angles[static_cast<std::size_t>(k)].inner_deg);
    const int axis = k / 4;                             // z, z, x, x, y, y pairs of pairs
    const int body = axis == 0 ? 2 : axis - 1;          // z, x, y
    const double sign = (k / 2) % 2 == 0 ? 1.0 : -1.0;  // up pair, then down pair
    EXPECT_NEAR(C_LB(2, body), sign, 1e-12) << "position " << k;
    if (k % 2 == 1) {
      // The partner has the same axis vertical and the horizontal axes reversed.
      const Eigen::Matrix3d prev =
          geometry.body_to_level(angles[static_cast<std::size_t>(k - 1)].outer_deg,
                                 angles[static_cast<std::size_t>(k - 1)].inner_deg);
      const int other = (body + 1) % 3;
      EXPECT_NEAR((C_LB.col(other) + prev.col(other)).norm(), 0.0, 1e-12) << "position " << k;
    }
  }
}

TEST(ClassicalTwelvePosition, RecoversAccelAndGyroNoiseless) {
  const sim::ImuTruth truth = full_truth();
  const TwelvePositionResult r =
      twelve_position(twelve_positions(truth), 9.7936, earth_rate_level_dps());
  expect_matches_truth(r.accel, truth.accel_bias, truth.accel_scale, truth.accel_misalignment,
                       1e-12, 1e-7, 1e-12);
  expect_matches_truth(r.gyro, truth.gyro_bias, truth.gyro_scale, truth.gyro_misalignment, 1e-14,
                       1e-6, 1e-12);
  EXPECT_EQ(r.accel.dof, 8);
  EXPECT_FALSE(r.gyro_g_sensitivity.has_value());
}

// Means at arbitrary attitudes: the mount rotation of a table at zero angles is C_LB itself.
std::vector<StaticPosition> positions_at(const sim::ImuTruth& truth,
                                         const std::array<Eigen::Matrix3d, 12>& attitudes) {
  std::vector<StaticPosition> out;
  for (const Eigen::Matrix3d& C_LB : attitudes) {
    core::TableGeometry geometry;
    geometry.mount_C_PB = C_LB;
    const sim::ImuInputs in = sim::imu_inputs(truth, geometry, test_site(), Eigen::Vector2d::Zero(),
                                              sim::TableKinematics{}, 25.0);
    const auto [gyro_err, accel_err] = sim::deterministic_errors(truth, in);
    out.push_back({in.rate_dps + gyro_err, in.force_mps2 + accel_err, C_LB});
  }
  return out;
}

TEST(ClassicalTwelvePosition, AttitudesMatchTableAngles) {
  const core::TableGeometry geometry;
  const auto angles = twelve_position_table_angles();
  const auto attitudes = twelve_position_attitudes(180.0);
  for (std::size_t k = 0; k < 12; ++k) {
    EXPECT_LT((attitudes[k] - geometry.body_to_level(angles[k].outer_deg, angles[k].inner_deg))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12)
        << "position " << k;
  }
  // And the attitude route gives the same fit as the table route.
  const sim::ImuTruth truth = full_truth();
  const TwelvePositionResult a =
      twelve_position(positions_at(truth, attitudes), 9.7936, earth_rate_level_dps());
  const TwelvePositionResult b =
      twelve_position(twelve_positions(truth), 9.7936, earth_rate_level_dps());
  EXPECT_LT((a.gyro.M - b.gyro.M).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((a.accel.M - b.accel.M).cwiseAbs().maxCoeff(), 1e-12);
}

sim::ImuTruth truth_with_g_sensitivity() {
  sim::ImuTruth truth = full_truth();
  truth.gyro_g_sensitivity << 2e-3, -1e-3, 0.5e-3,  //
      0.7e-3, 1.5e-3, -0.3e-3,                      //
      -0.2e-3, 0.9e-3, -1.8e-3;
  return truth;
}

TEST(ClassicalTwelvePosition, GyroGSensitivityRefusedOnTypicalTable) {
  // Body z never points North or South here: G[.][z] and M[.][z] are one combination, and the
  // error names it rather than fitting noise.
  TwelvePositionOptions options;
  options.fit_gyro_g_sensitivity = true;
  try {
    twelve_position(twelve_positions(truth_with_g_sensitivity()), 9.7936, earth_rate_level_dps(),
                    options);
    FAIL() << "inseparable g-sensitivity accepted";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("w_z"), std::string::npos) << what;
    EXPECT_NE(what.find("f_z"), std::string::npos) << what;
  }
}

TEST(ClassicalTwelvePosition, GyroGSensitivityWithHeadings0And90) {
  const sim::ImuTruth truth = truth_with_g_sensitivity();
  const auto positions = positions_at(truth, twelve_position_attitudes(90.0));
  TwelvePositionOptions options;
  options.fit_gyro_g_sensitivity = true;
  const TwelvePositionResult r =
      twelve_position(positions, 9.7936, earth_rate_level_dps(), options);
  ASSERT_TRUE(r.gyro_g_sensitivity.has_value());
  EXPECT_LT((*r.gyro_g_sensitivity - truth.gyro_g_sensitivity).cwiseAbs().maxCoeff(), 1e-12);
  expect_matches_truth(r.gyro, truth.gyro_bias, truth.gyro_scale, truth.gyro_misalignment, 1e-12,
                       1e-4, 1e-10);
  EXPECT_EQ(r.gyro.dof, 5);
  expect_matches_truth(r.accel, truth.accel_bias, truth.accel_scale, truth.accel_misalignment,
                       1e-12, 1e-7, 1e-12);
  // Without the G term the same data give a wrong gyro model: the test can see the difference.
  const TwelvePositionResult plain = twelve_position(positions, 9.7936, earth_rate_level_dps());
  EXPECT_GT((plain.gyro.M - r.gyro.M).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(ClassicalTwelvePosition, NoisyWithinThreeSigma) {
  const sim::ImuTruth truth = full_truth();
  auto positions = twelve_positions(truth);
  sim::NormalSource normal(99);
  for (StaticPosition& p : positions) {
    for (int i = 0; i < 3; ++i) {
      p.accel_mps2(i) += 1e-4 * normal.next();
      p.gyro_dps(i) += 1e-6 * normal.next();
    }
  }
  TwelvePositionOptions options;
  options.accel.measurement_sigma = Eigen::Vector3d::Constant(1e-4);
  options.gyro.measurement_sigma = Eigen::Vector3d::Constant(1e-6);
  const TwelvePositionResult r =
      twelve_position(positions, 9.7936, earth_rate_level_dps(), options);
  for (double z :
       normalised_errors(r.accel, truth.accel_bias, truth.accel_scale, truth.accel_misalignment)) {
    EXPECT_LT(std::abs(z), 3.0);
  }
  for (double z :
       normalised_errors(r.gyro, truth.gyro_bias, truth.gyro_scale, truth.gyro_misalignment)) {
    EXPECT_LT(std::abs(z), 3.0);
  }
}

TEST(ClassicalTwelvePosition, RefusesWrongCount) {
  auto positions = twelve_positions(full_truth());
  positions.pop_back();
  try {
    twelve_position(positions, 9.7936, earth_rate_level_dps());
    FAIL() << "eleven positions accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("11 positions given, need exactly 12"), std::string::npos)
        << e.what();
  }
}

// ------------------------------------------------------------------------------------------
// Rate tests

// Gyro z integrated over a turn of `angle_deg` about the vertical inner axis at `rate_dps`
// (z up). Midpoint rule: the misalignment terms are sinusoids of the table angle, integrated
// exactly over whole turns.
double integrated_z_deg(const sim::ImuTruth& truth, double rate_dps, double duration_s) {
  const int n = 7200;
  const double dt = duration_s / n;
  double angle = 0.0;
  for (int k = 0; k < n; ++k) {
    sim::TableKinematics table;
    const double t = (k + 0.5) * dt;
    table.inner_deg = rate_dps * t;
    table.inner_rate_dps = rate_dps;
    angle += exact_means(truth, table).gyro_dps.z() * dt;
  }
  return angle;
}

TEST(ClassicalRateTest, CwCcwRecoversBiasAndScaleWithEarthRate) {
  const sim::ImuTruth truth = full_truth();
  const double duration = 36.0;  // 10 deg/s for one turn each way
  const double cw = integrated_z_deg(truth, 10.0, duration);
  const double ccw = integrated_z_deg(truth, -10.0, duration);
  const RateTestResult r = rate_test_cw_ccw(cw, ccw, 360.0, duration, vertical_earth_rate_dps());
  EXPECT_NEAR(r.bias_dps, truth.gyro_bias.z(), 1e-12);
  EXPECT_NEAR(r.scale_ppm, truth.gyro_scale.z(), 1e-6);
  // The seed's closed form without (1+s) on the Earth term is off by s W_z.
  const double seed_bias = (cw + ccw) / (2.0 * duration) - vertical_earth_rate_dps();
  EXPECT_NEAR(seed_bias - r.bias_dps, 1e-6 * truth.gyro_scale.z() * vertical_earth_rate_dps(),
              1e-12);
  // Dropping the Earth term altogether turns W_z into bias.
  const RateTestResult no_earth = rate_test_cw_ccw(cw, ccw, 360.0, duration, 0.0);
  EXPECT_NEAR(no_earth.bias_dps - truth.gyro_bias.z(),
              (1.0 + 1e-6 * truth.gyro_scale.z()) * vertical_earth_rate_dps(), 1e-12);
}

TEST(ClassicalRateTest, CwCcwSigmaPropagation) {
  const double wz = vertical_earth_rate_dps();
  const double b = 0.004;
  const double s = -150e-6;
  const double theta = 720.0;
  const double t = 72.0;
  double sum_sq_b = 0.0;
  double sum_sq_s = 0.0;
  RateTestResult r;
  sim::NormalSource normal(5);
  const int trials = 2000;
  for (int k = 0; k < trials; ++k) {
    const double cw = (1.0 + s) * (theta + wz * t) + b * t + 0.01 * normal.next();
    const double ccw = (1.0 + s) * (-theta + wz * t) + b * t + 0.01 * normal.next();
    r = rate_test_cw_ccw(cw, ccw, theta, t, wz, 0.01);
    sum_sq_b += std::pow((r.bias_dps - b) / r.bias_sigma_dps, 2);
    sum_sq_s += std::pow((r.scale_ppm - 1e6 * s) / r.scale_sigma_ppm, 2);
  }
  EXPECT_NEAR(std::sqrt(sum_sq_b / trials), 1.0, 0.05);
  EXPECT_NEAR(std::sqrt(sum_sq_s / trials), 1.0, 0.05);
  EXPECT_EQ(r.sigma_source, SigmaSource::kGiven);
}

TEST(ClassicalRateTest, MeanRatesAtPlusMinusTableRate) {
  const sim::ImuTruth truth = full_truth();
  // A step mean over whole turns is the integrated angle over the step's duration.
  const double pos = integrated_z_deg(truth, 20.0, 18.0) / 18.0;
  const double neg = integrated_z_deg(truth, -20.0, 18.0) / 18.0;
  const RateTestResult r = rate_test_cw_ccw_rates(pos, neg, 20.0, vertical_earth_rate_dps());
  EXPECT_NEAR(r.bias_dps, truth.gyro_bias.z(), 1e-12);
  EXPECT_NEAR(r.scale_ppm, truth.gyro_scale.z(), 1e-6);
}

TEST(ClassicalRateTest, RateStepsLineFit) {
  const sim::ImuTruth truth = full_truth();
  const double wz = vertical_earth_rate_dps();
  std::vector<RateStep> steps;
  for (double rate : {-100.0, -30.0, -10.0, 10.0, 30.0, 100.0}) {
    const double duration = 360.0 / std::abs(rate);
    steps.push_back({rate, integrated_z_deg(truth, rate, duration) / duration});
  }
  const RateTestResult exact = rate_steps(steps, wz);
  EXPECT_NEAR(exact.bias_dps, truth.gyro_bias.z(), 1e-12);
  EXPECT_NEAR(exact.scale_ppm, truth.gyro_scale.z(), 1e-6);

  sim::NormalSource normal(11);
  for (RateStep& s : steps) s.gyro_mean_dps += 2e-3 * normal.next();
  const RateTestResult noisy = rate_steps(steps, wz);
  EXPECT_EQ(noisy.sigma_source, SigmaSource::kResidualScatter);
  EXPECT_LT(std::abs(noisy.bias_dps - truth.gyro_bias.z()), 3.0 * noisy.bias_sigma_dps);
  EXPECT_LT(std::abs(noisy.scale_ppm - truth.gyro_scale.z()), 3.0 * noisy.scale_sigma_ppm);
  EXPECT_GT(noisy.bias_sigma_dps, 0.0);
  const RateTestResult given = rate_steps(steps, wz, 2e-3);
  // Line-fit variances with x = r + W_z: mean x = W_z, Sxx = 2 (100^2 + 30^2 + 10^2).
  EXPECT_NEAR(given.bias_sigma_dps, 2e-3 * std::sqrt(1.0 / 6.0 + wz * wz / 22000.0), 1e-12);
  EXPECT_NEAR(given.scale_sigma_ppm, 1e6 * 2e-3 / std::sqrt(22000.0), 1e-9);
  EXPECT_EQ(given.sigma_source, SigmaSource::kGiven);
}

TEST(ClassicalRateTest, RefusesBadInput) {
  EXPECT_THROW(rate_test_cw_ccw(10.0, -10.0, 0.0, 1.0, 0.0), core::InputError);
  EXPECT_THROW(rate_test_cw_ccw(10.0, -10.0, 10.0, 0.0, 0.0), core::InputError);
  EXPECT_THROW(rate_test_cw_ccw_rates(10.0, -10.0, 0.0, 0.0), core::InputError);
  try {
    rate_steps({{10.0, 10.1}, {10.0, 10.2}}, 0.0);
    FAIL() << "one distinct rate accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("1 distinct table rates"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace calstand::solver

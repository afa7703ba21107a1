#include "solver/model.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "sim/imu_sim.hpp"
#include "sim_run.hpp"

namespace calstand::solver {
namespace {

using testing::wuhan_site;

TEST(ModelParse, NamesEveryParameterOfTheContract) {
  const Model m =
      Model::parse("gyro_bias,gyro_misalignment,gyro_temp_bias:2,earth_rate,table_tilt");
  std::vector<std::string> names;
  for (const auto& p : m.parameters()) names.push_back(p.name);
  const std::vector<std::string> expected{
      "gyro_bias.x",          "gyro_bias.y",          "gyro_bias.z",
      "gyro_misalignment.xy", "gyro_misalignment.xz", "gyro_misalignment.yx",
      "gyro_misalignment.yz", "gyro_misalignment.zx", "gyro_misalignment.zy",
      "gyro_temp_bias.x1",    "gyro_temp_bias.y1",    "gyro_temp_bias.z1",
      "gyro_temp_bias.x2",    "gyro_temp_bias.y2",    "gyro_temp_bias.z2",
      "table_tilt.east",      "table_tilt.north"};
  EXPECT_EQ(names, expected);
  EXPECT_TRUE(m.earth_rate());
  EXPECT_EQ(m.text(), "gyro_bias,gyro_misalignment,gyro_temp_bias:2,earth_rate,table_tilt");
  EXPECT_EQ(m.parameters()[9].unit, "deg/s/degC^k");
}

TEST(ModelParse, RefusesBadTermsWithASuggestion) {
  try {
    (void)Model::parse("gyro_bias,gyro_sacle");
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean \"gyro_scale\""), std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)Model::parse("gyro_bias,gyro_bias"), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_scale:2"), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_temp_bias:0"), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_temp_bias:x"), core::InputError);
  EXPECT_THROW((void)Model::parse(""), core::InputError);
}

TEST(ModelParse, CustomTermsAreCheckedBeforeAnyDataIsRead) {
  const Model m = Model::parse("gyro_bias", {"grad=gyro:temperature_rate"});
  ASSERT_EQ(m.size(), 6u);
  EXPECT_EQ(m.parameters()[3].name, "grad.x");
  EXPECT_THROW((void)Model::parse("gyro_bias", {"grad=gyro:temperature_rat"}), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_bias", {"grad=magnet:elapsed"}), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_bias", {"gyro_bias=gyro:elapsed"}), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_bias", {"grad=gyro:(elapsed"}), core::InputError);
  EXPECT_THROW((void)Model::parse("gyro_bias", {"no equals sign"}), core::InputError);
}

// Draws a value of a typical magnitude for a parameter's unit.
double typical_value(const ParameterInfo& p, sim::NormalSource& normal) {
  double value = 1e-2 * normal.next();
  if (p.unit == "rad") value = 1e-3 * normal.next();
  if (p.unit == "ppm" || p.unit == "ppm/degC" || p.unit == "ug/g^2") value = 300.0 * normal.next();
  if (p.unit == "ppm/(deg/s)") value = 0.5 * normal.next();
  if (p.unit == "m") value = 0.05 * normal.next();
  if (p.unit == "deg/s/degC^k" || p.unit == "m/s^2/degC^k") value = 1e-4 * normal.next();
  return value;
}

// The regressors times the true parameters must reproduce the simulator's deterministic errors
// at arbitrary table states and temperatures, one catalogue term at a time (with earth_rate, so
// the reference is the simulator's true input): the solver and the simulator implement the same
// contract independently.
class ModelRegressorsPerTerm : public ::testing::TestWithParam<std::string> {};

TEST_P(ModelRegressorsPerTerm, ReproduceTheSimulatorsErrors) {
  std::mt19937_64 engine(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  sim::NormalSource normal(11);
  const std::string term = GetParam();
  const Model model = Model::parse(term == "earth_rate" ? term : term + ",earth_rate");
  sim::ImuTruth truth;
  truth.temperature_ref_c = 20.0;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.size()));
  Eigen::Vector2d tilt = Eigen::Vector2d::Zero();
  for (std::size_t p = 0; p < model.size(); ++p) {
    const ParameterInfo& info = model.parameters()[p];
    const double value = typical_value(info, normal);
    theta[static_cast<Eigen::Index>(p)] = value;
    if (info.name == "table_tilt.east")
      tilt.x() = value;
    else if (info.name == "table_tilt.north")
      tilt.y() = value;
    else
      truth.set_parameter(info.name, value);
  }
  core::TableGeometry geometry;
  geometry.outer_axis = Eigen::Vector3d(0.3, 0.9, 0.1).normalized();
  geometry.inner_axis = Eigen::Vector3d(0.1, -0.2, 1.0).normalized();
  RunSetup setup;
  setup.site = wuhan_site();
  setup.geometry = geometry;
  setup.temperature_ref_c = truth.temperature_ref_c;
  const SignalBuilder build(setup, model.earth_rate());
  Eigen::MatrixXd g(kChannels, static_cast<Eigen::Index>(model.size()));
  for (int trial = 0; trial < 30; ++trial) {
    sim::TableKinematics k;
    k.outer_deg = 360.0 * unit(engine) - 180.0;
    k.inner_deg = 360.0 * unit(engine) - 180.0;
    k.outer_rate_dps = trial % 3 == 0 ? 0.0 : 200.0 * normal.next();
    k.inner_rate_dps = trial % 2 == 0 ? 0.0 : 300.0 * normal.next();
    const double temp = -40.0 + 120.0 * unit(engine);
    const sim::ImuInputs in = sim::imu_inputs(truth, geometry, setup.site, tilt, k, temp);
    const auto [gyro_err, accel_err] = sim::deterministic_errors(truth, in);
    Vector6d simulated;
    simulated << in.rate_dps + gyro_err, in.force_mps2 + accel_err;

    core::ImuSample sample;
    sample.temperature_c = temp;
    const Signals s =
        build(sample, {k.outer_deg, k.inner_deg, k.outer_rate_dps, k.inner_rate_dps}, 0.0, 0.0);
    model.regressors(s, g);
    const Vector6d modelled = model.reference(s) + g * theta;
    // Exact up to what the linear model leaves out: the tilt squared (g t^2 / 2, about 1e-5
    // m/s^2 at 1.5 mrad, and W t^2 in the gyros).
    for (int c = 0; c < kChannels; ++c) {
      const double tolerance = c < kAx ? 1e-8 * (1.0 + in.rate_dps.norm()) : 3e-5;
      EXPECT_NEAR(modelled[c], simulated[c], tolerance)
          << term << " trial " << trial << " channel " << channel_name(c);
    }
  }
}

std::vector<std::string> catalogue_terms() {
  std::vector<std::string> out;
  for (const auto& t : core::error_term_catalogue()) {
    out.push_back(std::string(t.name) + (t.polynomial_order ? ":3" : ""));
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(EveryTerm, ModelRegressorsPerTerm, ::testing::ValuesIn(catalogue_terms()),
                         [](const auto& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n)
                             if (c == ':') c = '_';
                           return n;
                         });

}  // namespace
}  // namespace calstand::solver

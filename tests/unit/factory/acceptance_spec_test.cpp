// Acceptance specifications: the form tests outside the project use is accepted as written, a
// limit in another unit than its parameters' is refused by name, and every mistake a schema or
// the hand checks find is listed with its place in the file.
#include "factory/acceptance_spec.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/json_schema.hpp"

namespace calstand::analysis {
namespace {

// The form the issue fixes, byte for byte.
constexpr const char* kRequiredForm =
    R"js({"format": "calstand-acceptance/1", "name": "...", "k": 2, "limits": [{"parameter": )js"
    R"js("gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"}, {"parameter": "gyro_scale.*", )js"
    R"js("max_abs": 2000, "unit": "ppm"}, {"fit": "chi2_dof", "max": 2.0}]})js";

std::string spec_with_limits(const std::string& limits) {
  return R"js({"format": "calstand-acceptance/1", "name": "t", "limits": [)js" + limits + "]}";
}

// Every violation message of a refused specification, one per line, or "" when it parses.
std::string spec_refusal(const std::string& text) {
  try {
    parse_acceptance_spec(text, "spec.json");
  } catch (const core::SchemaError& e) {
    std::string lines;
    for (const auto& v : e.violations()) lines += v.path + ": " + v.message + "\n";
    return lines;
  } catch (const core::InputError& e) {
    return std::string(e.what()) + "\n";
  }
  return "";
}

TEST(AcceptanceSpec, TheRequiredFormIsAcceptedAsWritten) {
  const AcceptanceSpec spec = parse_acceptance_spec(kRequiredForm, "spec.json");
  EXPECT_EQ(spec.name, "...");
  EXPECT_EQ(spec.file, "spec.json");
  EXPECT_DOUBLE_EQ(spec.k, 2.0);
  ASSERT_EQ(spec.limits.size(), 3u);
  EXPECT_EQ(spec.limits[0].kind, LimitKind::kParameter);
  EXPECT_EQ(spec.limits[0].pattern, "gyro_bias.*");
  EXPECT_EQ(spec.limits[0].unit, "deg/s");
  ASSERT_TRUE(spec.limits[0].value.max_abs);
  EXPECT_DOUBLE_EQ(*spec.limits[0].value.max_abs, 0.005);
  EXPECT_FALSE(spec.limits[0].value.min || spec.limits[0].value.max);
  EXPECT_EQ(spec.limits[1].pattern, "gyro_scale.*");
  EXPECT_DOUBLE_EQ(*spec.limits[1].value.max_abs, 2000.0);
  EXPECT_EQ(spec.limits[2].kind, LimitKind::kFit);
  EXPECT_EQ(spec.limits[2].pattern, "chi2_dof");
  EXPECT_EQ(spec.limits[2].unit, "");
  ASSERT_TRUE(spec.limits[2].value.max);
  EXPECT_DOUBLE_EQ(*spec.limits[2].value.max, 2.0);
  EXPECT_EQ(spec.limits[2].where, "limits[2]");
  EXPECT_FALSE(spec.validation);
}

TEST(AcceptanceSpec, KDefaultsToTwoAndTheHashIsOfTheBytes) {
  const std::string a = spec_with_limits(R"js({"fit": "chi2_dof", "max": 2})js");
  const std::string b = a + "\n";  // the same document, other bytes
  const AcceptanceSpec sa = parse_acceptance_spec(a, "a.json");
  EXPECT_DOUBLE_EQ(sa.k, 2.0);
  EXPECT_NE(sa.sha256, parse_acceptance_spec(b, "b.json").sha256);
  // The hash as sha256sum computes it of the same bytes.
  const std::string path =
      ::testing::TempDir() + "calstand-spec-hash-" + std::to_string(::getpid()) + ".json";
  std::ofstream(path, std::ios::binary) << a;
  FILE* pipe = popen(("sha256sum " + path).c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char digest[65] = {};
  const std::size_t n = fread(digest, 1, 64, pipe);
  pclose(pipe);
  std::filesystem::remove(path);
  ASSERT_EQ(n, 64u) << "sha256sum gave no digest";
  EXPECT_EQ(sa.sha256, std::string(digest, 64));
}

TEST(AcceptanceSpec, ALimitInAnotherUnitThanItsParametersIsRefusedByName) {
  const std::string why = spec_refusal(
      spec_with_limits(R"js({"parameter": "gyro_bias.*", "max_abs": 18, "unit": "deg/h"})js"));
  EXPECT_NE(why.find("limits[0].unit"), std::string::npos) << why;
  EXPECT_NE(why.find("\"deg/h\""), std::string::npos) << why;
  EXPECT_NE(why.find("gyro_bias.*"), std::string::npos) << why;
  EXPECT_NE(why.find("deg/s"), std::string::npos) << why;  // the unit the parameter has
}

TEST(AcceptanceSpec, EveryRefusedLimitIsListed) {
  const std::string why = spec_refusal(spec_with_limits(
      R"js({"parameter": "gyro_bias.*", "max_abs": 18, "unit": "deg/h"},
         {"parameter": "accel_scale.*", "max_abs": 500, "unit": "ppm"},
         {"parameter": "accel_bias.x", "max_abs": 0.01, "unit": "g"})js"));
  EXPECT_NE(why.find("limits[0].unit"), std::string::npos) << why;
  EXPECT_EQ(why.find("limits[1]"), std::string::npos) << why;
  EXPECT_NE(why.find("limits[2].unit"), std::string::npos) << why;
  EXPECT_NE(why.find("m/s^2"), std::string::npos) << why;
}

TEST(AcceptanceSpec, UnknownFieldsAreRefusedWithTheirPlace) {
  std::string why = spec_refusal(
      R"js({"format": "calstand-acceptance/1", "name": "t", "limitz": [], "limits": [{"fit": "chi2_dof", "max": 2}]})js");
  EXPECT_NE(why.find("limitz"), std::string::npos) << why;
  why = spec_refusal(
      spec_with_limits(R"js({"parameter": "gyro_bias.*", "max_ab": 0.01, "unit": "deg/s"})js"));
  EXPECT_NE(why.find("limits[0]"), std::string::npos) << why;
  EXPECT_NE(why.find("max_ab"), std::string::npos) << why;
}

TEST(AcceptanceSpec, SchemaRulesAreChecked) {
  EXPECT_NE(
      spec_refusal(
          R"js({"format": "calstand-acceptance/2", "name": "t", "limits": [{"fit": "chi2_dof", "max": 2}]})js"),
      "");
  EXPECT_NE(
      spec_refusal(
          R"js({"format": "calstand-acceptance/1", "limits": [{"fit": "chi2_dof", "max": 2}]})js"),
      "");                                            // no name
  EXPECT_NE(spec_refusal(spec_with_limits("")), "");  // no limit
  // A parameter limit without a unit, and one that limits nothing.
  EXPECT_NE(spec_refusal(spec_with_limits(R"js({"parameter": "gyro_bias.*", "max_abs": 0.01})js")),
            "");
  EXPECT_NE(spec_refusal(spec_with_limits(R"js({"parameter": "gyro_bias.*", "unit": "deg/s"})js")),
            "");
  EXPECT_NE(spec_refusal(spec_with_limits(R"js({"fit": "chi2", "max": 2})js")), "");
  EXPECT_NE(
      spec_refusal(spec_with_limits(R"js({"fit": "chi2_dof", "max": 2}], "k": -1, "x": [)js")), "");
  EXPECT_NE(spec_refusal(spec_with_limits(R"js({"temperature_range_c": [10]})js")), "");
  // Bad JSON names the file.
  const std::string why = spec_refusal("{\"format\": ");
  EXPECT_NE(why.find("spec.json"), std::string::npos) << why;
}

TEST(AcceptanceSpec, PatternsMatchTheCatalogue) {
  AcceptanceSpec spec = parse_acceptance_spec(
      spec_with_limits(R"js({"parameter": "*_misalignment.*", "max_abs": 0.001, "unit": "rad"},
                          {"parameter": "gyro_temp_bias.*", "max_abs": 0.001, "unit": "deg/s/degC^k"},
                          {"parameter": "accel_scale.x", "min": -500, "max": 500, "unit": "ppm"},
                          {"parameter": "gyro_scale*", "max_sigma": 20, "unit": "ppm"})js"),
      "spec.json");
  ASSERT_EQ(spec.limits.size(), 4u);
  EXPECT_TRUE(spec.limits[3].max_sigma);
  EXPECT_FALSE(spec.limits[3].value.max_abs || spec.limits[3].value.min);
  EXPECT_DOUBLE_EQ(*spec.limits[2].value.min, -500.0);

  // A pattern matching nothing is a typo, with the term it most likely meant.
  std::string why = spec_refusal(
      spec_with_limits(R"js({"parameter": "gyro_bais.*", "max_abs": 0.01, "unit": "deg/s"})js"));
  EXPECT_NE(why.find("limits[0].parameter"), std::string::npos) << why;
  EXPECT_NE(why.find("matches no parameter"), std::string::npos) << why;
  EXPECT_NE(why.find("gyro_bias.*"), std::string::npos) << why;
  // A pattern over terms of different units cannot have one unit.
  why = spec_refusal(
      spec_with_limits(R"js({"parameter": "*_bias.*", "max_abs": 0.01, "unit": "deg/s"})js"));
  EXPECT_NE(why.find("different units"), std::string::npos) << why;
  EXPECT_NE(why.find("accel_bias in m/s^2"), std::string::npos) << why;
  // The diagonal of a misalignment is not a parameter.
  why = spec_refusal(spec_with_limits(
      R"js({"parameter": "gyro_misalignment.xx", "max_abs": 0.01, "unit": "rad"})js"));
  EXPECT_NE(why.find("matches no parameter"), std::string::npos) << why;
}

TEST(AcceptanceSpec, NoiseFitAndTemperatureLimits) {
  const AcceptanceSpec spec = parse_acceptance_spec(
      spec_with_limits(R"js({"noise": "gyro_arw.*", "max": 0.15, "unit": "deg/sqrt(h)"},
                          {"noise": "accel_bias_instability.z", "max": 50, "unit": "ug"},
                          {"fit": "rms_gyro", "max": 0.001},
                          {"fit": "rms_accel", "max": 0.001, "unit": "m/s^2"},
                          {"temperature_range_c": [-40, 85]})js"),
      "spec.json");
  ASSERT_EQ(spec.limits.size(), 5u);
  EXPECT_EQ(spec.limits[0].kind, LimitKind::kNoise);
  EXPECT_EQ(spec.limits[2].unit, "deg/s");  // a fit figure's unit when none is written
  EXPECT_EQ(spec.limits[4].kind, LimitKind::kTemperatureRange);
  EXPECT_DOUBLE_EQ(spec.limits[4].temperature_min_c, -40.0);
  EXPECT_DOUBLE_EQ(spec.limits[4].temperature_max_c, 85.0);

  std::string why = spec_refusal(
      spec_with_limits(R"js({"noise": "gyro_arw.*", "max": 0.15, "unit": "deg/s/sqrt(Hz)"})js"));
  EXPECT_NE(why.find("deg/sqrt(h)"), std::string::npos) << why;
  why = spec_refusal(spec_with_limits(R"js({"fit": "chi2_dof", "max": 2, "unit": "1"})js"));
  EXPECT_NE(why.find("limits[0].unit"), std::string::npos) << why;
  why = spec_refusal(spec_with_limits(R"js({"fit": "rms_gyro", "max": 2, "unit": "rad/s"})js"));
  EXPECT_NE(why.find("deg/s"), std::string::npos) << why;
  why = spec_refusal(spec_with_limits(R"js({"temperature_range_c": [85, -40]})js"));
  EXPECT_NE(why.find("limits[0].temperature_range_c"), std::string::npos) << why;
  why = spec_refusal(spec_with_limits(
      R"js({"parameter": "accel_scale.x", "min": 10, "max": -10, "unit": "ppm"})js"));
  EXPECT_NE(why.find("above max"), std::string::npos) << why;
  why = spec_refusal(spec_with_limits(
      R"js({"parameter": "accel_scale.x", "max_abs": 10, "max": 10, "unit": "ppm"})js"));
  EXPECT_NE(why.find("max_abs with min or max"), std::string::npos) << why;
}

TEST(AcceptanceSpec, AValidationPartTakesParameterAndFitLimitsAndAModel) {
  const AcceptanceSpec spec = parse_acceptance_spec(
      R"js({"format": "calstand-acceptance/1", "name": "v", "limits": [{"fit": "chi2_dof", "max": 2}],
          "validation": {"model": ["accel_bias", "gyro_bias", "earth_rate"],
                         "limits": [{"parameter": "accel_bias.*", "max_abs": 0.001, "unit": "m/s^2"},
                                    {"fit": "chi2_dof", "max": 3}]}})js",
      "spec.json");
  ASSERT_TRUE(spec.validation);
  EXPECT_EQ(spec.validation->model.size(), 3u);
  ASSERT_EQ(spec.validation->limits.size(), 2u);
  EXPECT_EQ(spec.validation->limits[0].where, "validation.limits[0]");

  // Noise has no place in a validation fit; a term must be one of the catalogue's.
  EXPECT_NE(
      spec_refusal(
          R"js({"format": "calstand-acceptance/1", "name": "v", "limits": [{"fit": "chi2_dof", "max": 2}],
          "validation": {"limits": [{"noise": "gyro_arw.*", "max": 1, "unit": "deg/sqrt(h)"}]}})js"),
      "");
  const std::string why = spec_refusal(
      R"js({"format": "calstand-acceptance/1", "name": "v", "limits": [{"fit": "chi2_dof", "max": 2}],
          "validation": {"model": ["accel_bias", "gyro_bais"], "limits": [{"fit": "chi2_dof", "max": 3}]}})js");
  EXPECT_NE(why.find("validation.model[1]"), std::string::npos) << why;
}

TEST(AcceptanceSpec, AFileIsReadWithTheHashOfItsBytes) {
  const std::string path =
      ::testing::TempDir() + "calstand-spec-" + std::to_string(::getpid()) + ".json";
  std::ofstream(path) << kRequiredForm;
  const AcceptanceSpec from_file = read_acceptance_spec(path);
  EXPECT_EQ(from_file.file, path);
  EXPECT_EQ(from_file.sha256, parse_acceptance_spec(kRequiredForm, "x").sha256);
  std::filesystem::remove(path);
  try {
    read_acceptance_spec(path);
    FAIL() << "a missing file was read";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), path);
  }
}

}  // namespace
}  // namespace calstand::analysis

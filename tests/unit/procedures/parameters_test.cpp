// `--set NAME=VALUE` overrides: parsing and checks against the declared parameters.
#include <gtest/gtest.h>

#include "procedures/procedure.hpp"
#include "test_util.hpp"

namespace calstand::procedures {
namespace {

using nlohmann::json;

Procedure with_parameters() {
  return test::parse(test::doc_with(
      R"([{"kind": "for_each", "var": "t", "values": "${temps}", "steps": [
            {"kind": "capture", "duration_s": "${capture_s}", "label": "${t} ${axis}"}]}])",
      R"({"capture_s": {"default": 30, "min": 1, "description": "s"},
          "temps": {"default": [25], "min": -55, "max": 125, "description": "degC"},
          "axis": {"default": "outer", "description": "axis"}})"));
}

std::vector<Violation> resolve_violations(const Procedure& p, const Overrides& o) {
  try {
    resolve_parameters(p, o);
  } catch (const ProcedureError& e) {
    return e.violations();
  }
  ADD_FAILURE() << "resolved without error";
  return {};
}

TEST(ParseOverrides, ValuesAreJsonElseText) {
  const Overrides o = parse_overrides(
      {"capture_s=30", "temperatures=[-40,25,85]", "axis=outer", "name=\"quoted\"", "x=1.5e2"});
  EXPECT_EQ(o.at("capture_s"), 30);
  EXPECT_EQ(o.at("temperatures"), json({-40, 25, 85}));
  EXPECT_EQ(o.at("axis"), "outer");
  EXPECT_EQ(o.at("name"), "quoted");
  EXPECT_DOUBLE_EQ(o.at("x").get<double>(), 150.0);
}

TEST(ParseOverrides, RefusesMalformedArguments) {
  try {
    parse_overrides({"capture_s"});
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "--set capture_s");
    EXPECT_EQ(std::string(e.what()), "--set capture_s: expected NAME=VALUE, e.g. capture_s=30");
  }
  EXPECT_THROW(parse_overrides({"=5"}), core::InputError);
  try {
    parse_overrides({"a=1", "a=2"});
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_EQ(std::string(e.what()), "--set a: is given more than once");
  }
}

TEST(ResolveParameters, OverridesReplaceDefaults) {
  const auto values =
      resolve_parameters(with_parameters(), parse_overrides({"temps=[-40,25,85]", "capture_s=5"}));
  EXPECT_EQ(values.at("temps"), json({-40, 25, 85}));
  EXPECT_EQ(values.at("capture_s"), 5);
  EXPECT_EQ(values.at("axis"), "outer");  // default kept

  const auto steps = expand(with_parameters(), parse_overrides({"temps=[-40,85]", "axis=inner"}));
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_EQ(steps[0].label, "-40 inner");
  EXPECT_EQ(steps[1].label, "85 inner");
  EXPECT_DOUBLE_EQ(steps[1].duration_s, 30.0);
}

TEST(ResolveParameters, UnknownNameIsAnError) {
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"capture", 5}}), "--set capture",
                       "capture is not a parameter of t (it has axis, capture_s, temps)");
}

TEST(ResolveParameters, ScalarOfTheWrongTypeIsAnError) {
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"capture_s", "abc"}}),
                       "--set capture_s",
                       "\"abc\" is not a number (parameter capture_s is a number)");
}

TEST(ResolveParameters, ScalarForAListIsAnError) {
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"temps", 25}}), "--set temps",
                       "25 is not a list (parameter temps is a number_list)");
}

TEST(ResolveParameters, ListElementOfTheWrongTypeIsAnError) {
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"temps", json({25, "hot"})}}),
                       "--set temps[1]",
                       "\"hot\" is not a number (parameter temps is a number_list)");
}

TEST(ResolveParameters, ValueOutsideMinMaxIsAnError) {
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"capture_s", 0}}), "--set capture_s",
                       "0 is below the minimum 1");
  EXPECT_ONE_VIOLATION(resolve_violations(with_parameters(), {{"temps", json({25, 150})}}),
                       "--set temps[1]", "150 is above the maximum 125");
}

TEST(ResolveParameters, EveryBadOverrideIsListed) {
  const auto vs =
      resolve_violations(with_parameters(), {{"axis", 3}, {"capture_s", -1}, {"nope", 1}});
  ASSERT_EQ(vs.size(), 3u) << test::lines(vs);
  EXPECT_EQ(vs[0].path, "--set axis");
  EXPECT_EQ(vs[1].path, "--set capture_s");
  EXPECT_EQ(vs[2].path, "--set nope");
}

}  // namespace
}  // namespace calstand::procedures

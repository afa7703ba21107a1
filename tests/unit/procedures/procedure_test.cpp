// Parsing: JSON text, schema, and the rules that need no parameter values (one bad procedure
// per rule, exact path and message).
#include "procedures/procedure.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "procedures/library.hpp"
#include "test_util.hpp"

namespace calstand::procedures {
namespace {

using nlohmann::json;
using test::doc_with;
using test::parse;
using test::parse_violations;

TEST(ParseProcedure, ReadsNameParametersAndText) {
  const json doc = doc_with(R"([{"kind": "capture", "duration_s": "${capture_s}", "label": "z"}])",
                            R"({"capture_s": {"default": 30, "min": 1, "description": "s"},
                                "temps": {"default": [-40, 85], "description": "degC"},
                                "axes": {"default": ["outer"], "description": "a"},
                                "none": {"default": [], "type": "number_list", "description": "e"}})");
  const std::string text = doc.dump();
  const Procedure p = parse_procedure(text, "dir/t.json");
  EXPECT_EQ(p.name, "t");
  EXPECT_EQ(p.file_name, "dir/t.json");
  EXPECT_EQ(p.source_text, text);
  EXPECT_EQ(p.parameters.at("capture_s"), 30);
  EXPECT_EQ(p.parameters.at("temps"), json({-40, 85}));
  EXPECT_EQ(p.parameter_specs.at("capture_s").type, ParameterSpec::Type::kNumber);
  EXPECT_EQ(p.parameter_specs.at("temps").type, ParameterSpec::Type::kNumberList);
  EXPECT_EQ(p.parameter_specs.at("axes").type, ParameterSpec::Type::kStringList);
  EXPECT_EQ(p.parameter_specs.at("none").type, ParameterSpec::Type::kNumberList);
  EXPECT_EQ(*p.parameter_specs.at("capture_s").min, 1.0);
  EXPECT_FALSE(p.parameter_specs.at("capture_s").max.has_value());
}

TEST(ParseProcedure, JsonSyntaxErrorNamesFileLineAndColumn) {
  try {
    parse_procedure("{\n  \"format\": \"calstand-procedure/1\",\n  \"name\" \"t\"\n}", "bad.json");
    FAIL() << "expected an InputError";
  } catch (const ProcedureError&) {
    FAIL() << "a syntax error is not a rule violation";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "bad.json:3:12");
  }
}

TEST(ParseProcedure, ListsEverySchemaViolationWithItsPath) {
  json doc = doc_with(R"([
    {"kind": "move", "outer_deg": 0},
    {"kind": "rate", "axis": "outer", "rate_dps": true, "duration_s": 5},
    {"kind": "spin"},
    {"kind": "for_each", "var": "a", "values": [1], "steps": [{"kind": "capture", "duration_s": 1}]},
    {"kind": "set_temperature", "target_c": 25, "soak": {"tolerance_c": 1, "stable_s": 1}}])");
  doc["extra"] = 1;
  const auto vs = parse_violations(doc);
  ASSERT_EQ(vs.size(), 6u) << test::lines(vs);
  EXPECT_EQ(vs[0].path, "");
  EXPECT_EQ(vs[0].message, "unknown property \"extra\"");
  EXPECT_EQ(vs[1].path, "steps[0]");
  EXPECT_EQ(vs[1].message, "missing required property \"inner_deg\"");
  EXPECT_EQ(vs[2].path, "steps[1].rate_dps");
  EXPECT_EQ(vs[2].message, "expected a string or a number, got a boolean");
  EXPECT_EQ(vs[3].path, "steps[2].kind");
  EXPECT_EQ(vs[4].path, "steps[3].steps[0]");
  EXPECT_EQ(vs[4].message, "missing required property \"label\"");
  EXPECT_EQ(vs[5].path, "steps[4].soak");
  EXPECT_EQ(vs[5].message, "missing required property \"timeout_s\"");
}

TEST(ParseProcedure, SchemaViolationsComeAloneBeforeTheRules) {
  // steps[0] breaks the schema, steps[1] a rule: only the schema is reported.
  const auto vs = parse_violations(
      doc_with(R"([{"kind": "wait"}, {"kind": "wait", "duration_s": "${nothing}"}])"));
  EXPECT_ONE_VIOLATION(vs, "steps[0]", "missing required property \"duration_s\"");
}

TEST(ParseProcedure, ErrorTextNamesTheFileOnEveryLine) {
  try {
    parse_procedure(doc_with(R"([{"kind": "wait", "duration_s": "${a}"},
                                 {"kind": "wait", "duration_s": "${b}"}])")
                        .dump(),
                    "p.json");
    FAIL();
  } catch (const ProcedureError& e) {
    EXPECT_EQ(e.where(), "p.json");
    EXPECT_EQ(
        std::string(e.what()),
        "p.json: steps[0].duration_s: ${a} refers to no parameter or enclosing loop variable\n"
        "p.json: steps[1].duration_s: ${b} refers to no parameter or enclosing loop variable");
  }
}

// --- Parameter declarations -------------------------------------------------------------------

TEST(ParameterRules, EmptyListDefaultNeedsADeclaredType) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(R"([{"kind": "wait", "duration_s": 1}])",
                                                 R"({"l": {"default": [], "description": "d"}})")),
                       "parameters.l.default",
                       "[] is empty, so its type cannot be inferred; declare \"type\"");
}

TEST(ParameterRules, ListDefaultMustNotMixNumbersAndStrings) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "wait", "duration_s": 1}])",
                                R"({"l": {"default": [1, "a"], "description": "d"}})")),
      "parameters.l.default", "[1, \"a\"] mixes numbers and strings");
}

TEST(ParameterRules, DefaultMustHaveTheDeclaredType) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "wait", "duration_s": 1}])",
                           R"({"x": {"default": "abc", "type": "number", "description": "d"}})")),
                       "parameters.x.default", "\"abc\" is not a number (parameter x is a number)");
}

TEST(ParameterRules, DefaultMustNotBeBelowTheMinimum) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "wait", "duration_s": 1}])",
                                R"({"x": {"default": 0, "min": 1, "description": "d"}})")),
      "parameters.x.default", "0 is below the minimum 1");
}

TEST(ParameterRules, ListElementsMustNotExceedTheMaximum) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "wait", "duration_s": 1}])",
                           R"({"r": {"default": [10, 500], "max": 400, "description": "d"}})")),
                       "parameters.r.default[1]", "500 is above the maximum 400");
}

TEST(ParameterRules, MinOnlyAppliesToNumbers) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "wait", "duration_s": 1}])",
                                R"({"s": {"default": "a", "min": 1, "description": "d"}})")),
      "parameters.s.min", "applies only to numbers, and s is a string");
}

TEST(ParameterRules, MinMustNotExceedMax) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "wait", "duration_s": 1}])",
                           R"({"x": {"default": 3, "min": 5, "max": 1, "description": "d"}})")),
                       "parameters.x.min", "5 is above max 1");
}

// --- References and steps ----------------------------------------------------------------------

TEST(StepRules, NumericFieldTextMustBeAReference) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(R"([{"kind": "wait", "duration_s": "sixty"}])")),
                       "steps[0].duration_s",
                       "\"sixty\" is neither a number nor a reference ${name}");
}

TEST(StepRules, ReferenceMustNameAParameterOrLoopVariable) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "capture", "duration_s": "${capture}", "label": "a"}])",
                           R"({"capture_s": {"default": 1, "description": "d"}})")),
                       "steps[0].duration_s",
                       "${capture} refers to no parameter or enclosing loop variable");
}

TEST(StepRules, LoopVariableIsOnlyInScopeInsideItsLoop) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(R"([
        {"kind": "for_each", "var": "d", "values": [1], "steps": [{"kind": "wait", "duration_s": "${d}"}]},
        {"kind": "wait", "duration_s": "${d}"}])")),
                       "steps[1].duration_s",
                       "${d} refers to no parameter or enclosing loop variable");
}

TEST(StepRules, LabelReferencesMustBeInScope) {
  EXPECT_ONE_VIOLATION(
      parse_violations(
          doc_with(R"([{"kind": "capture", "duration_s": 1, "label": "at ${nope}"}])")),
      "steps[0].label", "${nope} refers to no parameter or enclosing loop variable");
}

TEST(StepRules, NumericFieldMustNotReferenceAListParameter) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "set_temperature", "target_c": "${temps}"}])",
                                R"({"temps": {"default": [1, 2], "description": "d"}})")),
      "steps[0].target_c", "${temps} is a number_list parameter, not a number");
}

TEST(StepRules, AxisMustBeOuterInnerOrAReference) {
  EXPECT_ONE_VIOLATION(
      parse_violations(
          doc_with(R"([{"kind": "rate", "axis": "middle", "rate_dps": 10, "duration_s": 1}])")),
      "steps[0].axis", "\"middle\" is not \"outer\", \"inner\" or a reference ${name}");
}

TEST(StepRules, AxisMustNotReferenceANumberParameter) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "rate", "axis": "${n}", "rate_dps": 10, "duration_s": 1}])",
                           R"({"n": {"default": 1, "description": "d"}})")),
                       "steps[0].axis", "${n} is a number parameter, not a string");
}

TEST(StepRules, RateNeedsDurationOrRevolutionsNotBoth) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "rate", "axis": "outer", "rate_dps": 10, "duration_s": 1, "revolutions": 1}])")),
      "steps[0]", "has both duration_s and revolutions; give exactly one");
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "rate", "axis": "outer", "rate_dps": 10}])")),
      "steps[0]", "has neither duration_s nor revolutions; give exactly one");
}

TEST(StepRules, MoveGivesBothAnglesOrUpNotBoth) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "move", "up": "+x", "outer_deg": 0}])")), "steps[0]",
      "has both up and table angles; give outer_deg and inner_deg, or up");
  // Without up, the schema asks for the angles (ParseProcedure.ListsEverySchemaViolation...).
  EXPECT_EQ(parse_violations(doc_with(R"([{"kind": "move"}])")).size(), 2u);
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "move", "outer_deg": 0, "inner_deg": 0, "imu": "a"}])")),
                       "steps[0].imu", "names the IMU whose body axis up points; it needs up");
}

TEST(StepRules, UpMustBeABodyDirectionOrAStringReference) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "move", "up": "x"}])")), "steps[0].up",
      R"("x" is not a body direction ("+x", "-x", "+y", "-y", "+z", "-z") or a reference ${name})");
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(R"([{"kind": "move", "up": "${n}"}])",
                                                 R"({"n": {"default": 1, "description": "d"}})")),
                       "steps[0].up", "${n} is a number parameter, not a string");
  // A loop over directions: each value is checked as the loop expands.
  const Procedure loop = parse(doc_with(
      R"([{"kind": "for_each", "var": "d", "values": ["+z", "-z", "+w"], "steps": [
            {"kind": "move", "up": "${d}"}]}])"));
  EXPECT_ONE_VIOLATION(test::expand_violations(loop), "steps[0].steps[0].up",
                       R"(${d} = "+w" is not one of "+x", "-x", "+y", "-y", "+z", "-z")");
}

TEST(LoopRules, LoopVariableMustNotShadowAParameter) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "for_each", "var": "t", "values": [1], "steps": [{"kind": "wait", "duration_s": 1}]}])",
          R"({"t": {"default": 1, "description": "d"}})")),
      "steps[0].var", "\"t\" shadows the parameter t");
}

TEST(LoopRules, LoopVariableMustNotShadowAnEnclosingLoop) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(R"([{"kind": "for_each", "var": "a", "values": [1], "steps": [
          {"kind": "for_each", "var": "a", "values": [2], "steps": [{"kind": "wait", "duration_s": 1}]}]}])")),
      "steps[0].steps[0].var", "\"a\" shadows the variable of the enclosing loop steps[0]");
}

TEST(LoopRules, LiteralValuesMustNotBeEmpty) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "for_each", "var": "a", "values": [], "steps": [{"kind": "wait", "duration_s": 1}]}])")),
      "steps[0].values", "[] is empty: the loop would run no steps");
}

TEST(LoopRules, LoopStepsMustNotBeEmpty) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with(
                           R"([{"kind": "for_each", "var": "a", "values": [1], "steps": []}])")),
                       "steps[0].steps", "[] is empty: the loop would run no steps");
}

TEST(LoopRules, ValuesTextMustBeAReference) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "for_each", "var": "a", "values": "1,2", "steps": [{"kind": "wait", "duration_s": 1}]}])")),
      "steps[0].values", "\"1,2\" is neither a list nor a reference ${name} to a list parameter");
}

TEST(LoopRules, ValuesMustReferenceAParameter) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "for_each", "var": "a", "values": "${temps}", "steps": [{"kind": "wait", "duration_s": 1}]}])")),
      "steps[0].values", "${temps} refers to no list parameter");
}

TEST(LoopRules, ValuesMustReferenceAListParameter) {
  EXPECT_ONE_VIOLATION(
      parse_violations(doc_with(
          R"([{"kind": "for_each", "var": "a", "values": "${n}", "steps": [{"kind": "wait", "duration_s": 1}]}])",
          R"({"n": {"default": 3, "description": "d"}})")),
      "steps[0].values", "${n} is a number parameter, not a list");
}

TEST(ProcedureRules, ProcedureMustHaveSteps) {
  EXPECT_ONE_VIOLATION(parse_violations(doc_with("[]")), "steps",
                       "[] is empty: the procedure has no steps");
}

TEST(ProcedureRules, EveryRuleBrokenIsListedInDocumentOrder) {
  const auto vs = parse_violations(doc_with(R"([
      {"kind": "wait", "duration_s": "${a}"},
      {"kind": "rate", "axis": "up", "rate_dps": "fast", "duration_s": 1},
      {"kind": "for_each", "var": "x", "values": [], "steps": [{"kind": "capture", "duration_s": 1, "label": "${y}"}]}])",
                                            R"({"x": {"default": [], "description": "d"}})"));
  ASSERT_EQ(vs.size(), 6u) << test::lines(vs);
  EXPECT_EQ(vs[0].path, "parameters.x.default");
  EXPECT_EQ(vs[1].path, "steps[0].duration_s");
  EXPECT_EQ(vs[2].path, "steps[1].rate_dps");
  EXPECT_EQ(vs[3].path, "steps[1].axis");
  // x failed its declaration, so it is not a parameter and the loop variable shadows nothing.
  EXPECT_EQ(vs[4].path, "steps[2].values");
  EXPECT_EQ(vs[5].path, "steps[2].steps[0].label");
}

// --- Loading by name or path --------------------------------------------------------------------

TEST(LoadProcedure, FindsLibraryNamesFirstThenFiles) {
  const Procedure lib = load_procedure("six-position");
  EXPECT_EQ(lib.name, "six-position");
  EXPECT_EQ(lib.file_name, "library/six-position.json");

  const auto path = std::filesystem::temp_directory_path() / "calstand_procedure_test.json";
  {
    std::ofstream out(path);
    out << doc_with(R"([{"kind": "wait", "duration_s": 5}])").dump(2);
  }
  const Procedure file = load_procedure(path.string());
  EXPECT_EQ(file.name, "t");
  EXPECT_EQ(file.file_name, path.string());
  std::filesystem::remove(path);
}

TEST(LoadProcedure, UnknownNameListsTheLibrary) {
  try {
    load_procedure("seven-position");
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "seven-position");
    EXPECT_NE(std::string(e.what()).find("six-position"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace calstand::procedures

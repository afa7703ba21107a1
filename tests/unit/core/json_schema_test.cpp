#include "core/json_schema.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/schemas.hpp"

namespace calstand::core {
namespace {

using nlohmann::json;
using Lines = std::vector<std::string>;

// Violations as "path: message" lines ("message" at the root), so a test states the exact text
// a user would read.
Lines check(const json& schema, const json& doc) {
  Lines lines;
  for (const auto& v : JsonSchema::parse(schema, "test.schema.json").validate(doc)) {
    lines.push_back(v.path.empty() ? v.message : v.path + ": " + v.message);
  }
  return lines;
}

// The text of the InputError a schema load throws, or "" when it loads.
std::string load_error(const json& schema) {
  try {
    JsonSchema::parse(schema, "test.schema.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// The text of the InputError parse_json_text throws, or "" when it parses.
std::string parse_error(std::string_view text) {
  try {
    parse_json_text(text, "station.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// Keywords

TEST(JsonSchemaType, NamesExpectedAndActualType) {
  const json s = {{"type", "number"}};
  EXPECT_EQ(check(s, 1.5), Lines{});
  EXPECT_EQ(check(s, 3), Lines{});
  EXPECT_EQ(check(s, "fast"), Lines{"expected a number, got a string"});
  EXPECT_EQ(check(s, nullptr), Lines{"expected a number, got null"});
  EXPECT_EQ(check({{"type", "object"}}, json::array()), Lines{"expected an object, got an array"});
}

TEST(JsonSchemaType, IntegerAcceptsIntegralNumbersOnly) {
  const json s = {{"type", "integer"}};
  EXPECT_EQ(check(s, 4), Lines{});
  EXPECT_EQ(check(s, 4.0), Lines{});
  EXPECT_EQ(check(s, 4.5), Lines{"expected an integer, got 4.5"});
  EXPECT_EQ(check(s, true), Lines{"expected an integer, got a boolean"});
}

TEST(JsonSchemaType, ArrayOfTypesAcceptsAnyOfThem) {
  const json s = {{"type", {"string", "null"}}};
  EXPECT_EQ(check(s, "x"), Lines{});
  EXPECT_EQ(check(s, nullptr), Lines{});
  EXPECT_EQ(check(s, 7), Lines{"expected a string or null, got a number"});
}

TEST(JsonSchemaType, MismatchSuppressesTheOtherRulesAtThatPath) {
  // One mistake, one message: the enum would only repeat that 5 is not a string.
  EXPECT_EQ(check({{"type", "string"}, {"enum", {"a", "b"}}}, 5),
            Lines{"expected a string, got a number"});
}

TEST(JsonSchemaEnum, ListsAllowedValues) {
  const json s = {{"enum", {"position", "rate"}}};
  EXPECT_EQ(check(s, "rate"), Lines{});
  EXPECT_EQ(check(s, "fast"), Lines{R"("fast" is not one of "position", "rate")"});
  EXPECT_EQ(check({{"enum", {2, 4, 8}}}, 4.0), Lines{});  // numbers compare by value
  EXPECT_EQ(check({{"enum", {2, 4, 8}}}, 3), Lines{"3 is not one of 2, 4, 8"});
}

TEST(JsonSchemaConst, NamesRequiredValue) {
  const json s = {{"const", "calstand-truth/1"}};
  EXPECT_EQ(check(s, "calstand-truth/1"), Lines{});
  EXPECT_EQ(check(s, "calstand-truth/2"),
            Lines{R"("calstand-truth/2" is not the required value "calstand-truth/1")"});
}

TEST(JsonSchemaObject, RequiredAndPropertiesAtNestedPaths) {
  const json s = json::parse(R"({
    "type": "object",
    "properties": {"imus": {"type": "array", "items": {
      "type": "object", "required": ["name", "port"],
      "properties": {"name": {"type": "string"}, "port": {"type": "integer"}}}}}
  })");
  EXPECT_EQ(check(s, json::parse(R"({"imus": [{"name": "a", "port": 1}, {"port": "x"}]})")),
            (Lines{R"(imus[1]: missing required property "name")",
                   "imus[1].port: expected an integer, got a string"}));
}

TEST(JsonSchemaObject, UnknownPropertySuggestsCloseName) {
  const json s = json::parse(R"({
    "properties": {"rate_dps": {"type": "number"}, "duration_s": {"type": "number"}},
    "additionalProperties": false
  })");
  EXPECT_EQ(check(s, json::parse(R"({"rate_dps": 1})")), Lines{});
  EXPECT_EQ(check(s, json::parse(R"({"rat_dps": 1})")),
            Lines{R"(unknown property "rat_dps" (did you mean "rate_dps"?))"});
  EXPECT_EQ(check(s, json::parse(R"({"rtae_dps": 1})")),  // a swap counts as one edit
            Lines{R"(unknown property "rtae_dps" (did you mean "rate_dps"?))"});
  EXPECT_EQ(check(s, json::parse(R"({"colour": 1})")), Lines{R"(unknown property "colour")"});
}

TEST(JsonSchemaObject, AdditionalPropertiesSchemaChecksTheExtraValues) {
  const json s = {{"properties", {{"name", {{"type", "string"}}}}},
                  {"additionalProperties", {{"type", "number"}}}};
  EXPECT_EQ(check(s, {{"name", "x"}, {"gain", 2}}), Lines{});
  EXPECT_EQ(check(s, {{"name", "x"}, {"gain", "high"}}),
            Lines{"gain: expected a number, got a string"});
}

TEST(JsonSchemaObject, PatternPropertiesMatchKeysByRegex) {
  const json s = json::parse(R"({
    "patternProperties": {"^[a-z_]+\\.[a-z0-9]+$": {"type": "number"}},
    "additionalProperties": false
  })");
  EXPECT_EQ(check(s, json::parse(R"({"gyro_bias.x": 0.1})")), Lines{});
  EXPECT_EQ(check(s, json::parse(R"({"gyro_bias.x": "big"})")),
            Lines{R"(["gyro_bias.x"]: expected a number, got a string)"});
  EXPECT_EQ(check(s, json::parse(R"({"GyroBias": 0.1})")), Lines{R"(unknown property "GyroBias")"});
}

TEST(JsonSchemaObject, PropertyNamesCheckEveryKey) {
  const json s = {{"propertyNames", {{"pattern", "^[a-z]+$"}}}};
  EXPECT_EQ(check(s, {{"abc", 1}}), Lines{});
  EXPECT_EQ(check(s, {{"Abc", 1}}),
            Lines{R"(Abc: invalid property name: "Abc" does not match the pattern "^[a-z]+$")"});
}

TEST(JsonSchemaArray, ItemsPrefixItemsAndCounts) {
  const json s = json::parse(R"({
    "prefixItems": [{"type": "string"}, {"type": "integer"}],
    "items": {"type": "number", "minimum": 0},
    "minItems": 3, "maxItems": 4
  })");
  EXPECT_EQ(check(s, json::parse(R"(["x", 1, 0.5])")), Lines{});
  EXPECT_EQ(
      check(s, json::parse(R"([1, "x"])")),
      (Lines{"has 2 items, fewer than the minimum of 3", "[0]: expected a string, got a number",
             "[1]: expected an integer, got a string"}));
  EXPECT_EQ(
      check(s, json::parse(R"(["x", 1, 2, 3, -1])")),
      (Lines{"has 5 items, more than the maximum of 4", "[4]: -1 is less than the minimum 0"}));
  EXPECT_EQ(check({{"minItems", 2}}, {1}), Lines{"has 1 item, fewer than the minimum of 2"});
}

TEST(JsonSchemaArray, UniqueItemsNamesTheDuplicates) {
  const json s = {{"uniqueItems", true}};
  EXPECT_EQ(check(s, {1, 2, 3}), Lines{});
  EXPECT_EQ(check(s, {1, 2, 1.0, 2}), (Lines{"items [0] and [2] are equal; items must be unique",
                                             "items [1] and [3] are equal; items must be unique"}));
  EXPECT_EQ(check(s, json::parse(R"([{"a": 1}, {"a": 1}])")),
            Lines{"items [0] and [1] are equal; items must be unique"});
}

TEST(JsonSchemaNumber, Bounds) {
  const json s = {{"minimum", 0}, {"maximum", 200}};
  EXPECT_EQ(check(s, 0), Lines{});
  EXPECT_EQ(check(s, 200), Lines{});
  EXPECT_EQ(check(s, 220), Lines{"220 is greater than the maximum 200"});
  EXPECT_EQ(check(s, -0.5), Lines{"-0.5 is less than the minimum 0"});
  EXPECT_EQ(check(s, "high"), Lines{});  // numeric rules ignore other types, as the standard says
  const json e = {{"exclusiveMinimum", 0}, {"exclusiveMaximum", 1.5}};
  EXPECT_EQ(check(e, 0.1), Lines{});
  EXPECT_EQ(check(e, 0), Lines{"0 is not greater than the exclusive minimum 0"});
  EXPECT_EQ(check(e, 1.5), Lines{"1.5 is not less than the exclusive maximum 1.5"});
}

TEST(JsonSchemaNumber, LargeIntegerBoundsCompareExactly) {
  // As doubles, 2^53 + 1 and 2^53 are the same number.
  const json s = {{"maximum", 9007199254740992}};
  EXPECT_EQ(check(s, 9007199254740992), Lines{});
  EXPECT_EQ(check(s, 9007199254740993),
            Lines{"9007199254740993 is greater than the maximum 9007199254740992"});
  EXPECT_EQ(check({{"maximum", 4294967295}}, 4294967296),
            Lines{"4294967296 is greater than the maximum 4294967295"});
}

TEST(JsonSchemaNumber, MultipleOfToleratesDecimalRounding) {
  EXPECT_EQ(check({{"multipleOf", 5}}, 15), Lines{});
  EXPECT_EQ(check({{"multipleOf", 5}}, 12), Lines{"12 is not a multiple of 5"});
  EXPECT_EQ(check({{"multipleOf", 0.1}}, 0.3), Lines{});  // 0.3 / 0.1 = 2.9999999999999996
  EXPECT_EQ(check({{"multipleOf", 0.25}}, 0.3), Lines{"0.3 is not a multiple of 0.25"});
}

TEST(JsonSchemaString, LengthCountsCharactersAndPatternIsUnanchored) {
  const json s = {{"minLength", 2}, {"maxLength", 3}};
  EXPECT_EQ(check(s, "ab"), Lines{});
  EXPECT_EQ(check(s, "\xC2\xB0\xC2\xB0\xC2\xB0"), Lines{});  // three degree signs, six bytes
  EXPECT_EQ(check(s, "a"), Lines{R"("a" is shorter than the minimum length of 2 characters)"});
  EXPECT_EQ(check(s, "abcd"), Lines{R"("abcd" is longer than the maximum length of 3 characters)"});
  const json p = {{"pattern", "[0-9]{3}"}};
  EXPECT_EQ(check(p, "sn-123-b"), Lines{});
  EXPECT_EQ(check(p, "sn-12"), Lines{R"("sn-12" does not match the pattern "[0-9]{3}")"});
}

TEST(JsonSchemaString, LongValuesAreShortenedInMessages) {
  const std::string long_value(200, 'x');
  const Lines lines = check({{"maxLength", 3}}, long_value);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_LT(lines[0].size(), 120u);
  EXPECT_NE(lines[0].find("..."), std::string::npos);
}

TEST(JsonSchemaString, OverlongStringIsReportedNotSearched) {
  // std::regex_search recurses per character and overflows the stack on strings like this one
  // (a segfault before the cap); the validator reports them instead.
  const json p = {{"pattern", "^[a-z]+$"}};
  EXPECT_EQ(check(p, std::string(50000, 'a')),
            Lines{"string of 50000 characters is too long to check against the pattern"});
  EXPECT_EQ(check(p, std::string(4096, 'a')), Lines{});  // at the cap: still checked
  EXPECT_EQ(check(p, std::string(4096, 'A')).size(), 1u);
  const json keys = {{"type", "object"},
                     {"patternProperties", {{"^[a-z]+$", {{"type", "number"}}}}},
                     {"additionalProperties", false}};
  EXPECT_EQ(check(keys, json{{std::string(50000, 'k'), 1}}),
            Lines{std::string(50000, 'k') +
                  ": property name of 50000 characters is too long to check against the pattern"});
}

// A document for `node` (resolving local $refs in `root`) with `big` in every place a string
// can go and as a key wherever patternProperties allow keys, to depth `depth`.
json fill_with(const json& root, const json& node, const std::string& big, int depth) {
  if (depth <= 0 || !node.is_object()) return big;
  if (auto ref = node.find("$ref"); ref != node.end()) {
    const std::string pointer = ref->get<std::string>().substr(1);  // "#/$defs/x" -> "/$defs/x"
    return fill_with(root, root.at(json::json_pointer(pointer)), big, depth - 1);
  }
  for (const char* combinator : {"oneOf", "anyOf", "allOf"}) {
    if (auto it = node.find(combinator); it != node.end() && !it->empty()) {
      return fill_with(root, it->front(), big, depth - 1);
    }
  }
  if (node.contains("properties") || node.contains("patternProperties")) {
    json obj = json::object();
    if (auto it = node.find("properties"); it != node.end()) {
      for (const auto& [key, sub] : it->items()) obj[key] = fill_with(root, sub, big, depth - 1);
    }
    if (auto it = node.find("patternProperties"); it != node.end() && !it->empty()) {
      obj[big] = fill_with(root, it->begin().value(), big, depth - 1);
    }
    return obj;
  }
  if (auto it = node.find("items"); it != node.end()) {
    return json::array({fill_with(root, *it, big, depth - 1)});
  }
  return big;
}

TEST(JsonSchemaString, ShippedSchemasSurviveAOneMegabyteString) {
  const std::string big(1 << 20, '7');
  const auto names = schema_text_names();
  ASSERT_FALSE(names.empty());
  for (const auto name : names) {
    const json root = parse_json_text(*schema_text(name), std::string(name));
    const JsonSchema schema = JsonSchema::parse(root, std::string(name));
    const json doc = fill_with(root, root, big, 12);
    ASSERT_TRUE(doc.is_object()) << name;
    std::vector<SchemaViolation> violations;
    EXPECT_NO_THROW(violations = schema.validate(doc)) << name;
    EXPECT_FALSE(violations.empty()) << name;  // "format" alone cannot be a megabyte of 7s
    for (const auto& v : violations) EXPECT_LT(v.message.size(), 300u) << name << " " << v.path;
    EXPECT_NO_THROW(schema.validate(json(big))) << name;
  }
}

// ---------------------------------------------------------------------------------------------
// Combinators

TEST(JsonSchemaCombinators, AllOfReportsEveryBranch) {
  const json s = json::parse(R"({"allOf": [{"minimum": 10}, {"multipleOf": 4}]})");
  EXPECT_EQ(check(s, 12), Lines{});
  EXPECT_EQ(check(s, 6), (Lines{"6 is less than the minimum 10", "6 is not a multiple of 4"}));
}

TEST(JsonSchemaCombinators, AnyOfWithOneFormOfTheRightTypeShowsItsProblems) {
  // The truth file's per-axis value: one number for all axes, or [x, y, z].
  const json s = json::parse(R"({"properties": {"arw": {"anyOf": [
    {"type": "number", "minimum": 0},
    {"type": "array", "items": {"type": "number", "minimum": 0}, "minItems": 3, "maxItems": 3}
  ]}}})");
  EXPECT_EQ(check(s, {{"arw", 0.1}}), Lines{});
  EXPECT_EQ(check(s, {{"arw", {0.1, 0.2, 0.3}}}), Lines{});
  EXPECT_EQ(check(s, {{"arw", {0.1, -0.2}}}),
            (Lines{"arw: matches none of the 2 allowed forms; closest is form 2, whose problems "
                   "follow",
                   "arw: has 2 items, fewer than the minimum of 3",
                   "arw[1]: -0.2 is less than the minimum 0"}));
  EXPECT_EQ(check(s, {{"arw", "low"}}), Lines{"arw: expected an array or a number, got a string"});
}

TEST(JsonSchemaCombinators, AnyOfWithoutAClearFavouriteGivesOnlyTheSummary) {
  const json s = json::parse(R"({"anyOf": [{"minimum": 10}, {"maximum": 2}]})");
  EXPECT_EQ(check(s, 5), Lines{"matches none of the 2 allowed forms"});
}

TEST(JsonSchemaCombinators, OneOfNamesFormsByDefinitionAndDiscriminator) {
  const json s = json::parse(R"({
    "type": "array",
    "items": {"oneOf": [{"$ref": "#/$defs/rate_step"}, {"$ref": "#/$defs/position_step"}]},
    "$defs": {
      "rate_step": {"type": "object", "required": ["kind", "rate_dps"], "properties": {
        "kind": {"const": "rate"}, "rate_dps": {"type": "number", "maximum": 200}}},
      "position_step": {"type": "object", "required": ["kind", "angle_deg"], "properties": {
        "kind": {"const": "position"}, "angle_deg": {"type": "number"}}}
    }
  })");
  EXPECT_EQ(check(s, json::parse(R"([{"kind": "rate", "rate_dps": 20},
                                     {"kind": "position", "angle_deg": 90}])")),
            Lines{});
  // The kind picks the form, so the user sees that form's problem, not the other's.
  EXPECT_EQ(check(s, json::parse(R"([{"kind": "rate", "rate_dps": 220}])")),
            (Lines{R"([0]: matches none of the 2 allowed forms; closest is form 1 ("rate_step"), )"
                   "whose problems follow",
                   "[0].rate_dps: 220 is greater than the maximum 200"}));
  EXPECT_EQ(check(s, json::parse(R"([{"kind": "fast"}])")),
            (Lines{"[0]: matches none of the 2 allowed forms",
                   R"([0].kind: "fast" is not one of "rate", "position")"}));
}

TEST(JsonSchemaCombinators, AFixedValueDeepInAFormIsThatFormsProblemNotItsDiscriminator) {
  // A chamber map: a built-in name, or an object whose written fields must be holding registers.
  const json s = json::parse(R"({"oneOf": [
    {"title": "built-in", "type": "string", "enum": ["watlow-f4"]},
    {"title": "map", "type": "object", "properties": {
      "setpoint": {"type": "object", "properties": {"kind": {"const": "holding"}}}}}
  ]})");
  EXPECT_EQ(check(s, json::parse(R"({"setpoint": {"kind": "input"}})")),
            (Lines{R"(matches none of the 2 allowed forms; closest is form 2 ("map"), whose )"
                   "problems follow",
                   R"(setpoint.kind: "input" is not the required value "holding")"}));
}

TEST(JsonSchemaCombinators, OneOfRejectsMatchingSeveralForms) {
  const json s =
      json::parse(R"({"oneOf": [{"type": "integer"}, {"minimum": 0, "title": "non-negative"}]})");
  EXPECT_EQ(check(s, -3), Lines{});
  EXPECT_EQ(check(s, 0.5), Lines{});
  EXPECT_EQ(check(s, 3),
            Lines{R"(matches 2 of the 2 allowed forms (form 1 and form 2 ("non-negative")); )"
                  "exactly one must match"});
}

TEST(JsonSchemaCombinators, Not) {
  const json s = json::parse(R"({"not": {"const": 0, "title": "zero"}})");
  EXPECT_EQ(check(s, 1), Lines{});
  EXPECT_EQ(check(s, 0), Lines{R"(matches a form that is not allowed ("zero"))"});
}

TEST(JsonSchemaCombinators, IfThenElse) {
  const json s = json::parse(R"({
    "if": {"properties": {"mode": {"const": "rate"}}},
    "then": {"required": ["rate_dps"]},
    "else": {"required": ["angle_deg"]}
  })");
  EXPECT_EQ(check(s, {{"mode", "rate"}, {"rate_dps", 1}}), Lines{});
  EXPECT_EQ(check(s, {{"mode", "rate"}}), Lines{R"(missing required property "rate_dps")"});
  EXPECT_EQ(check(s, {{"mode", "position"}}), Lines{R"(missing required property "angle_deg")"});
}

TEST(JsonSchemaBoolean, FalseSchemaRejectsAndTrueAccepts) {
  EXPECT_EQ(check(true, {{"a", 1}}), Lines{});
  EXPECT_EQ(check(false, 1), Lines{"no value is allowed here"});
  EXPECT_EQ(check({{"properties", {{"legacy", false}}}}, {{"legacy", 1}}),
            Lines{"legacy: no value is allowed here"});
}

// ---------------------------------------------------------------------------------------------
// $ref

TEST(JsonSchemaRef, ResolvesDefsDefinitionsAndRecursion) {
  const json s = json::parse(R"({
    "$ref": "#/$defs/node",
    "$defs": {"node": {"type": "object", "properties": {
      "value": {"$ref": "#/definitions/positive"},
      "children": {"type": "array", "items": {"$ref": "#/$defs/node"}}}}},
    "definitions": {"positive": {"type": "number", "exclusiveMinimum": 0}}
  })");
  EXPECT_EQ(check(s, json::parse(R"({"value": 1, "children": [{"value": 2}]})")), Lines{});
  EXPECT_EQ(check(s, json::parse(R"({"value": 1, "children": [{"children": [{"value": -1}]}]})")),
            Lines{"children[0].children[0].value: -1 is not greater than the exclusive minimum 0"});
}

TEST(JsonSchemaRef, AppliesAlongsideSiblingKeywords) {
  const json s =
      json::parse(R"({"$ref": "#/$defs/n", "maximum": 5, "$defs": {"n": {"minimum": 1}}})");
  EXPECT_EQ(check(s, 3), Lines{});
  EXPECT_EQ(check(s, 0), Lines{"0 is less than the minimum 1"});
  EXPECT_EQ(check(s, 6), Lines{"6 is greater than the maximum 5"});
}

TEST(JsonSchemaRef, LoopWithoutProgressEndsWithAViolation) {
  const json s = json::parse(R"({"$ref": "#/$defs/a", "$defs": {"a": {"$ref": "#/$defs/a"}}})");
  const Lines lines = check(s, 1);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("nested too deeply"), std::string::npos);
}

TEST(JsonSchemaRef, BadReferencesAreRejectedAtLoad) {
  EXPECT_EQ(load_error(json::parse(R"({"$ref": "#/$defs/missing"})")),
            R"(test.schema.json #/$ref: reference target "#/$defs/missing" does not exist)");
  EXPECT_NE(load_error(json::parse(R"({"$ref": "other.json#/a"})")).find("only references within"),
            std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Paths and collection

TEST(JsonSchemaPath, FormatsNestedArraysObjectsAndOddKeys) {
  const json s = json::parse(R"({"properties": {
    "grid": {"items": {"items": {"type": "number"}}},
    "odd key": {"properties": {"x": {"type": "number"}}},
    "a": {"properties": {"b": {"properties": {"c_1": {"type": "number"}}}}}
  }})");
  EXPECT_EQ(
      check(s, json::parse(R"({
    "grid": [[1, 2], [3, 4, "five"]],
    "odd key": {"x": "y"},
    "a": {"b": {"c_1": null}}
  })")),
      (Lines{"a.b.c_1: expected a number, got null", "grid[1][2]: expected a number, got a string",
             R"(["odd key"].x: expected a number, got a string)"}));
  EXPECT_EQ(check({{"items", {{"required", {"name"}}}}}, json::parse(R"([{}])")),
            Lines{R"([0]: missing required property "name")"});
}

TEST(JsonSchemaValidate, CollectsEveryViolation) {
  const json s = json::parse(R"({
    "type": "object", "required": ["name"], "additionalProperties": false,
    "properties": {"name": {"type": "string"},
                   "steps": {"type": "array", "items": {"type": "object",
                             "properties": {"rate_dps": {"maximum": 200}}}}}
  })");
  const json doc = json::parse(R"({"steps": [{"rate_dps": 10}, {"rate_dps": 220}], "colour": 1})");
  EXPECT_EQ(check(s, doc),
            (Lines{R"(missing required property "name")", R"(unknown property "colour")",
                   "steps[1].rate_dps: 220 is greater than the maximum 200"}));
}

TEST(JsonSchemaValidate, ThrowingFormListsEveryViolationWithFile) {
  const auto schema = JsonSchema::parse(json::parse(R"({
    "required": ["format"],
    "properties": {"steps": {"items": {"properties": {"rate_dps": {"maximum": 200}}}}}
  })"),
                                        "procedure.schema.json");
  EXPECT_NO_THROW(validate_or_throw(schema, {{"format", 1}}, "p.json"));
  try {
    validate_or_throw(schema, json::parse(R"({"steps": [{}, {}, {}, {"rate_dps": 220}]})"),
                      "p.json");
    FAIL() << "expected SchemaError";
  } catch (const SchemaError& e) {
    EXPECT_STREQ(e.what(),
                 "p.json: missing required property \"format\"\n"
                 "p.json: steps[3].rate_dps: 220 is greater than the maximum 200");
    EXPECT_EQ(e.where(), "p.json");
    ASSERT_EQ(e.violations().size(), 2u);
    EXPECT_EQ(e.violations()[1].path, "steps[3].rate_dps");
  }
}

// ---------------------------------------------------------------------------------------------
// Schema load checks

TEST(JsonSchemaLoad, UnknownKeywordIsRejectedWithSuggestion) {
  EXPECT_EQ(
      load_error(json::parse(R"({"properties": {"rate": {"maximun": 200}}})")),
      R"(test.schema.json #/properties/rate: unknown keyword "maximun" (did you mean "maximum"?))");
  EXPECT_NE(load_error(json::parse(R"({"minProperties": 1})")).find("not supported"),
            std::string::npos);
}

TEST(JsonSchemaLoad, AnnotationsAndExtensionKeysAreAccepted) {
  EXPECT_EQ(load_error(json::parse(R"({
    "$schema": "https://json-schema.org/draft/2020-12/schema", "$id": "x", "$comment": "c",
    "title": "t", "description": "d", "default": 1, "examples": [1], "x-units": "deg/s"
  })")),
            "");
}

TEST(JsonSchemaLoad, MalformedKeywordValuesAreRejected) {
  EXPECT_NE(load_error({{"minimum", "5"}}).find("#/minimum: must be a number"), std::string::npos);
  EXPECT_NE(load_error({{"minItems", -1}}).find("non-negative integer"), std::string::npos);
  EXPECT_NE(load_error({{"type", "float"}}).find(R"("float" is not a type)"), std::string::npos);
  EXPECT_NE(load_error({{"items", json::array({json::object()})}}).find("prefixItems"),
            std::string::npos);
  EXPECT_NE(load_error({{"pattern", "[a-"}}).find("invalid regular expression"), std::string::npos);
  EXPECT_NE(load_error({{"anyOf", json::array()}}).find("non-empty array"), std::string::npos);
  EXPECT_NE(load_error({{"properties", {{"a", 5}}}}).find("#/properties/a: a schema must be"),
            std::string::npos);
}

TEST(JsonSchemaLoad, RequiredNameThatNoPropertyAllowsIsRejected) {
  EXPECT_EQ(load_error(json::parse(R"({"properties": {"rate_dps": {}}, "required": ["rate_dsp"],
                                       "additionalProperties": false})")),
            "test.schema.json #/required: required property \"rate_dsp\" is not allowed by "
            "\"properties\" and \"additionalProperties\": false (did you mean \"rate_dps\"?)");
}

TEST(JsonSchemaLoad, EverySchemaShippedInSchemasFolderLoads) {
  const auto names = schema_text_names();
  ASSERT_FALSE(names.empty());
  for (const auto name : names) {
    EXPECT_NO_THROW(JsonSchema::parse(parse_json_text(*schema_text(name), std::string(name)),
                                      std::string(name)))
        << name;
  }
}

// ---------------------------------------------------------------------------------------------
// Parsing

TEST(ParseJsonText, SyntaxErrorNamesFileLineAndColumn) {
  // A missing comma: the parser notices at the end of the unexpected token "b", the 10th
  // character of line 2.
  const std::string e = parse_error("{\n\"a\": 1 \"b\": 2}");
  EXPECT_EQ(e.rfind("station.json:2:10: invalid JSON: ", 0), 0u) << e;
  // A bad literal shows up when the newline after it is read: one past the end of line 3.
  const std::string literal = parse_error("{\n  \"a\": 1,\n  \"b\": tru\n}");
  EXPECT_EQ(literal.rfind("station.json:3:11: invalid JSON: ", 0), 0u) << literal;
  const std::string trailing_comma = parse_error("{\"a\": 1,\n}");
  EXPECT_EQ(trailing_comma.rfind("station.json:2:1: ", 0), 0u) << trailing_comma;
}

TEST(ParseJsonText, ColumnCountsCharactersNotBytes) {
  // "°" is two bytes; the stray x is the 11th character of line 1.
  const std::string e = parse_error("{\"t\": \"\xC2\xB0\" x}");
  EXPECT_EQ(e.rfind("station.json:1:11: ", 0), 0u) << e;
}

TEST(ParseJsonText, EndOfInputPointsPastTheLastCharacter) {
  const std::string e = parse_error("{\"a\": [1, 2");
  EXPECT_EQ(e.rfind("station.json:1:12: ", 0), 0u) << e;
}

TEST(ParseJsonText, RepeatedKeyIsRejectedWithItsPath) {
  EXPECT_EQ(parse_error(R"({"steps": [{"x": 1}, {"rate_dps": 1, "rate_dps": 2}]})"),
            "station.json: steps[1]: key \"rate_dps\" appears more than once (only one value can "
            "be used)");
  EXPECT_EQ(parse_error(R"({"a": {"k": 1}, "b": {"k": 2}})"), "");  // same key, other objects
  EXPECT_EQ(parse_json_text(R"({"a": [1, {"b": null}]})", "x.json"),
            json::parse(R"({"a": [1, {"b": null}]})"));
}

TEST(ReadJsonFile, MissingFileNamesThePath) {
  try {
    read_json_file("/nonexistent/calstand/station.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "/nonexistent/calstand/station.json");
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

TEST(ReadJsonFile, ReadsAFileAndReportsErrorsByPath) {
  // The pid keeps parallel runs from several build trees apart.
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid());
  const std::string good = (dir / ("calstand_json_schema_good_" + tag + ".json")).string();
  const std::string bad = (dir / ("calstand_json_schema_bad_" + tag + ".json")).string();
  std::ofstream(good) << R"({"rate_dps": 20})";
  std::ofstream(bad) << "{\n\"rate_dps\": }";
  EXPECT_EQ(read_json_file(good), json({{"rate_dps", 20}}));
  try {
    read_json_file(bad);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), bad + ":2:13");
  }
  std::filesystem::remove(good);
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace calstand::core

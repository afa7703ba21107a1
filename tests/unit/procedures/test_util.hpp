#pragma once

// Helpers shared by the procedures tests: procedures written inline as JSON, and the violations
// a bad one gives.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "procedures/procedure.hpp"

namespace calstand::procedures::test {

/// A valid procedure with `steps` and `parameters` (text: JSON).
inline nlohmann::json doc_with(const std::string& steps, const std::string& parameters = "{}") {
  return nlohmann::json::parse(R"({"format": "calstand-procedure/1", "name": "t", "parameters": )" +
                               parameters + R"(, "steps": )" + steps + "}");
}

inline Procedure parse(const nlohmann::json& doc) { return parse_procedure(doc.dump(), "t.json"); }

/// The violations parse_procedure() reports for `doc`; fails the test if it parses.
inline std::vector<Violation> parse_violations(const nlohmann::json& doc) {
  try {
    parse(doc);
  } catch (const ProcedureError& e) {
    return e.violations();
  }
  ADD_FAILURE() << "parsed without error: " << doc.dump();
  return {};
}

/// The violations expand() reports; fails the test if it expands.
inline std::vector<Violation> expand_violations(const Procedure& p, const Overrides& o = {}) {
  try {
    expand(p, o);
  } catch (const ProcedureError& e) {
    return e.violations();
  }
  ADD_FAILURE() << "expanded without error";
  return {};
}

inline std::string lines(const std::vector<Violation>& vs) {
  std::string s;
  for (const auto& v : vs) s += v.path + ": " + v.message + "\n";
  return s;
}

/// Exactly one violation, with this path and message.
#define EXPECT_ONE_VIOLATION(violations, want_path, want_message)          \
  do {                                                                     \
    const auto vs_ = (violations);                                         \
    ASSERT_EQ(vs_.size(), 1u) << ::calstand::procedures::test::lines(vs_); \
    EXPECT_EQ(vs_[0].path, want_path);                                     \
    EXPECT_EQ(vs_[0].message, want_message);                               \
  } while (0)

}  // namespace calstand::procedures::test

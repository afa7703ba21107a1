#include "daemon/api/run_request.hpp"

#include <gtest/gtest.h>

namespace {

using calstand::daemon::api::parse_run_request;
using calstand::procedures::ProcedureError;

std::vector<std::string> violation_paths(const nlohmann::json& body) {
  try {
    parse_run_request(body);
  } catch (const ProcedureError& e) {
    std::vector<std::string> paths;
    for (const auto& v : e.violations()) paths.push_back(v.path);
    return paths;
  }
  return {};
}

TEST(RunRequest, ALibraryNameWithParameters) {
  const auto r =
      parse_run_request({{"procedure", "six-position"}, {"parameters", {{"capture_s", 5}}}});
  EXPECT_EQ(r.procedure.name, "six-position");
  EXPECT_EQ(r.overrides.at("capture_s"), 5);
}

TEST(RunRequest, AnInlineProcedureDocument) {
  const nlohmann::json doc = {
      {"format", "calstand-procedure/1"},
      {"name", "one-capture"},
      {"steps", {{{"kind", "capture"}, {"duration_s", 2}, {"label", "still"}}}}};
  const auto r = parse_run_request({{"procedure", doc}});
  EXPECT_EQ(r.procedure.name, "one-capture");
  EXPECT_EQ(r.procedure.file_name, "request.procedure");
}

TEST(RunRequest, EveryShapeProblemIsListed) {
  EXPECT_EQ(violation_paths({{"parameters", 3}, {"what", 1}}),
            (std::vector<std::string>{"what", "parameters", "procedure"}));
  EXPECT_EQ(violation_paths(nlohmann::json::array()), (std::vector<std::string>{""}));
}

TEST(RunRequest, NamesAreLibraryProceduresOnlyNeverFiles) {
  EXPECT_EQ(violation_paths({{"procedure", "/etc/passwd"}}),
            (std::vector<std::string>{"procedure"}));
  EXPECT_EQ(violation_paths({{"procedure", "../procedures/library/six-position.json"}}),
            (std::vector<std::string>{"procedure"}));
}

TEST(RunRequest, AnInvalidInlineProcedureGivesItsViolations) {
  EXPECT_FALSE(
      violation_paths({{"procedure", {{"name", "x"}, {"steps", {{{"kind", "fly"}}}}}}}).empty());
}

}  // namespace

// `calstand --help` grouped by task, and one example in each subcommand's help (issue 31).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"

namespace {

using calstand::testing::Result;
using calstand::testing::run;

struct HelpGroup {
  std::string heading;
  std::vector<std::string> commands;
};

// The groups of the top-level help, in order, each with its subcommands' names. A heading is
// a line "Name:" without indent after the options; a subcommand a line indented by two spaces.
std::vector<HelpGroup> help_groups(const std::string& help) {
  std::vector<HelpGroup> groups;
  std::istringstream in(help);
  std::string line;
  bool past_options = false;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] != ' ' && line.back() == ':') {
      if (line == "Options:") continue;
      past_options = true;
      groups.push_back({line.substr(0, line.size() - 1), {}});
    } else if (past_options && line.rfind("  ", 0) == 0 && line[2] != ' ') {
      groups.back().commands.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return groups;
}

TEST(CliHelp, SubcommandsStandInTaskGroupsInTheOrderAPersonMeetsThem) {
  const Result r = run("--help");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto groups = help_groups(r.out);
  std::vector<std::string> headings;
  std::size_t commands = 0;
  for (const auto& g : groups) {
    headings.push_back(g.heading);
    commands += g.commands.size();
    EXPECT_FALSE(g.commands.empty()) << g.heading;
  }
  // "Other" is where a subcommand missing from cli/src/help_layout.cpp lands.
  const std::vector<std::string> expected{"Start here",
                                          "Run a station",
                                          "Analyse a run",
                                          "The loop: model against measurement",
                                          "Without a table: hand-held and imported sessions",
                                          "The factory line",
                                          "The fleet",
                                          "Devices",
                                          "Simulation"};
  EXPECT_EQ(headings, expected) << r.out;
  EXPECT_GE(commands, 38u) << r.out;
  ASSERT_FALSE(groups.empty());
  EXPECT_EQ(groups.front().commands, std::vector<std::string>{"demo"});
}

TEST(CliHelp, EverySubcommandsHelpEndsWithAnExampleOfItself) {
  const Result top = run("--help");
  ASSERT_EQ(top.exit_code, 0) << top.out;
  std::size_t checked = 0;
  for (const auto& g : help_groups(top.out)) {
    for (const auto& command : g.commands) {
      const Result r = run(command + " --help");
      EXPECT_EQ(r.exit_code, 0) << command << ": " << r.out;
      const std::string example = "Example:\n  calstand " + command;
      const auto at = r.out.find(example);
      ASSERT_NE(at, std::string::npos) << command << ": " << r.out;
      const char next = r.out[at + example.size()];
      EXPECT_TRUE(next == ' ' || next == '\n') << command << ": " << r.out;
      ++checked;
    }
  }
  EXPECT_GE(checked, 38u);
}

}  // namespace

// The help's layout is a table, apart from the commands: where a subcommand stands and its one
// example are a question of the whole list (the order a person meets them), not of the command.
#include "help_layout.hpp"

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::cli {
namespace {

struct HelpEntry {
  std::string_view group;    ///< the task heading in `calstand --help`
  std::string_view command;  ///< the subcommand's name
  std::string_view example;  ///< one command line, shown under the subcommand's own help
};

// In the order of the top-level help: groups in the order of their first entry, commands in
// table order within a group. Examples use lab.db with run 1 (the thermal calibration of the
// first example under "Run a station") where a run is needed.
constexpr std::array kHelpTable{
    HelpEntry{"Start here", "demo", "calstand demo"},
    HelpEntry{"Run a station", "station", "calstand station --station lab.json"},
    HelpEntry{"Run a station", "plan",
              "calstand plan thermal-calibration --set 'temperatures=[-40,25,85]'"},
    HelpEntry{"Run a station", "run",
              "calstand run thermal-calibration --db lab.db --set 'temperatures=[-40,25,85]'"},
    HelpEntry{"Run a station", "runs", "calstand runs --db lab.db"},
    HelpEntry{"Run a station", "show", "calstand show --db lab.db --run 1"},
    HelpEntry{"Run a station", "submit", "calstand submit six-position --daemon 127.0.0.1:8765"},
    HelpEntry{"Run a station", "status", "calstand status 1"},
    HelpEntry{"Run a station", "watch", "calstand watch 1"},
    HelpEntry{"Run a station", "pause", "calstand pause 1 --now"},
    HelpEntry{"Run a station", "resume", "calstand resume 1"},
    HelpEntry{"Run a station", "skip", "calstand skip 1 --step 4 --reason 'chamber door open'"},
    HelpEntry{"Run a station", "abort", "calstand abort 1 --reason 'wrong fixture'"},
    HelpEntry{"Run a station", "export", "calstand export --db lab.db --run 1 --out run1/"},
    HelpEntry{"Run a station", "token",
              "calstand token add alice --role operator --file /etc/calstand/tokens.json"},
    HelpEntry{"Analyse a run", "analyze", "calstand analyze stability --db lab.db --run 2"},
    HelpEntry{"Analyse a run", "allan", "calstand allan --db lab.db --run 2 --channel gx"},
    HelpEntry{"Analyse a run", "noise", "calstand noise --db lab.db --run 2 --kalibr imu.yaml"},
    HelpEntry{"Analyse a run", "noise-id",
              "calstand noise-id --csv gyro.csv --column gz --rate 100 --units deg/s"},
    HelpEntry{"Analyse a run", "report", "calstand report --db lab.db --run 1 --out report.html"},
    HelpEntry{"Analyse a run", "units",
              "calstand units \"0.15 deg/sqrt(h)\" --to \"deg/s/sqrt(Hz)\""},
    HelpEntry{"The loop: model against measurement", "fit", "calstand fit --db lab.db --run 1"},
    HelpEntry{"The loop: model against measurement", "diagnose",
              "calstand diagnose --db lab.db --run 1"},
    HelpEntry{"The loop: model against measurement", "history",
              "calstand history --db lab.db --run 1"},
    HelpEntry{"The loop: model against measurement", "calibrate",
              "calstand calibrate --db lab.db --run 1 --model gyro_bias,gyro_scale,accel_bias"},
    HelpEntry{"The loop: model against measurement", "apply",
              "calstand apply --record calibration-run1-imu0.json --db lab.db --run 1"},
    HelpEntry{"The loop: model against measurement", "export-calibration",
              "calstand export-calibration --record calibration-run1-imu0.json --format px4 "
              "--out imu.params"},
    HelpEntry{"Without a table: hand-held and imported sessions", "import",
              "calstand import session/ --db lab.db"},
    HelpEntry{"The factory line", "accept",
              "calstand accept --db lab.db --run 1 --spec acceptance.json --junit verdicts.xml"},
    HelpEntry{"The factory line", "certificate",
              "calstand certificate --db lab.db --run 1 --device imu0 --out cert.pdf"},
    HelpEntry{"The factory line", "calibrations",
              "calstand calibrations --db lab.db --serial SN0001"},
    HelpEntry{"The factory line", "trend", "calstand trend --db lab.db --serial SN0001"},
    HelpEntry{"The factory line", "lot",
              "calstand lot --db lab.db --since 2026-01-01 --html lot.html"},
    HelpEntry{"The fleet", "sync",
              "calstand sync --db lab.db --to postgresql://station@central/fleet --password-file "
              "~/.pgpass"},
    HelpEntry{"The fleet", "fleet",
              "calstand fleet runs --from postgresql://reader@central/fleet --password-file "
              "~/.pgpass"},
    HelpEntry{"Devices", "device", "calstand device --station lab.json table get"},
    HelpEntry{"Simulation", "sim-station",
              "calstand sim-station --time-scale 20 --station-out lab.json"},
    HelpEntry{"Simulation", "sim-session", "calstand sim-session --kind ferraris --out session/"},
    HelpEntry{"Simulation", "truth-from-spec", "calstand truth-from-spec adis16488 --seed 3"},
    HelpEntry{"Simulation", "noise-study", "calstand noise-study --runs 100 --duration 3600"},
};

constexpr std::string_view kOtherGroup = "Other";

const HelpEntry* find_entry(std::string_view command) {
  const auto it = std::find_if(kHelpTable.begin(), kHelpTable.end(),
                               [&](const HelpEntry& e) { return e.command == command; });
  return it == kHelpTable.end() ? nullptr : &*it;
}

// CLI11 prints groups in the order their first subcommand was registered; main.cpp registers
// in name order (easy to merge), so the top level's subcommands are printed from the table.
class TaskFormatter : public CLI::Formatter {
 public:
  std::string make_subcommands(const CLI::App* app, CLI::AppFormatMode mode) const override {
    if (app->get_parent() != nullptr) return CLI::Formatter::make_subcommands(app, mode);
    std::vector<std::string_view> groups;
    for (const auto& e : kHelpTable) {
      if (std::find(groups.begin(), groups.end(), e.group) == groups.end())
        groups.push_back(e.group);
    }
    groups.push_back(kOtherGroup);
    const auto subcommands = app->get_subcommands({});
    const auto print = [&](const CLI::App* sub) {
      return mode == CLI::AppFormatMode::All ? sub->help(sub->get_name(), CLI::AppFormatMode::Sub)
                                             : make_subcommand(sub);
    };
    std::string out;
    for (const auto group : groups) {
      std::string block;
      for (const CLI::App* sub : subcommands) {  // the table's order first, then the rest
        const HelpEntry* entry = find_entry(sub->get_name());
        if (entry == nullptr && sub->get_group() == group) block += print(sub);
      }
      std::string listed;
      for (const auto& e : kHelpTable) {
        if (e.group != group) continue;
        for (const CLI::App* sub : subcommands) {
          if (sub->get_name() == e.command) listed += print(sub);
        }
      }
      block = listed + block;
      if (!block.empty()) out += "\n" + std::string(group) + ":\n" + block;
    }
    return out;
  }
};

}  // namespace

void arrange_help(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands({})) {
    const HelpEntry* entry = find_entry(sub->get_name());
    if (entry == nullptr) {
      sub->group(std::string(kOtherGroup));
      continue;
    }
    sub->group(std::string(entry->group));
    const std::string example = "Example:\n  " + std::string(entry->example) + "\n";
    const std::string earlier = sub->get_footer();
    sub->footer(earlier.empty() ? example : example + "\n" + earlier);
  }
  app.formatter(std::make_shared<TaskFormatter>());
}

}  // namespace calstand::cli

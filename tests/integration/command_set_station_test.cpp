// Chambers and tables in the words of the controllers labs own: `calstand sim-station` serves
// the simulated chamber and table in a built-in command set (--chamber-protocol,
// --table-protocol), and `calstand run` drives them through the command-set drivers with the
// station file sim-station wrote. A thermal calibration across two plateaus, a six-position and
// a rate ladder each fit as well as on the in-process simulator.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "cli_runner.hpp"
#include "fit_quality.hpp"
#include "known_imu_station.hpp"
#include "sim_station_process.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::run;
using calstand::testing::SimStationProcess;
using calstand::testing::write_text;
using nlohmann::json;

// As the other sim-station tests: fast enough for the suite, slow enough for a busy machine.
constexpr const char* kSetsTimeScale = "20";

/// One table set and one chamber set served together, and how the station file names them.
struct SetPair {
  const char* table;
  const char* chamber;
  const char* table_backend;
  const char* chamber_backend;
};

/// The pair by its sets in ctest's test names (not the struct's bytes).
void PrintTo(const SetPair& p, std::ostream* os) { *os << p.table << " and " << p.chamber; }

class CommandSetStations : public ::testing::TestWithParam<SetPair> {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-command-sets-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static calstand::testing::Result run_procedure(const std::string& procedure,
                                                 const std::string& station,
                                                 const std::string& db) {
    return run("run " + procedure + " --station " + station + " --db " + db + " --quiet");
  }
  static json fit_json(const std::string& db, const std::string& args) {
    const auto r = run("fit --db " + db + " --run 1 " + args + " --json", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    return json::parse(r.out);
  }
  static std::string events_text(const std::string& db) {
    const auto r = run("show --db " + db + " --run 1 --json", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    std::string text;
    // Parsed into a name first: a range over a temporary's member dangles (before C++23 the
    // temporary dies before the loop; AddressSanitizer: heap-use-after-free).
    const json shown = json::parse(r.out);
    for (const auto& e : shown.at("events")) text += e.dump() + "\n";
    return text;
  }

  static inline std::string dir_;
};

TEST_P(CommandSetStations, CampaignsThroughTheControllersWordsFitAsWellAsInProcess) {
  const SetPair p = GetParam();
  const std::string name = std::string(p.table) + "-" + p.chamber;
  const std::string sim = dir_ + name + "-sim.json";
  write_text(sim, calstand::testing::known_imu_station(name, 11));
  // Short, so that four pairs fit the suite: two plateaus from the ambient (a soak to a far
  // plateau is most of a thermal run's time), the table's turns and positions for the gyro
  // fit; the accelerometers from their own six positions.
  const std::string thermal =
      "thermal-calibration --set temperatures=[23,24] --set final_c=24 --set final_soak_s=5 --set "
      "soak_s=5 "
      "--set capture_s=5 --set ramp_c_per_min=5 --set outer_angles=[0,180] "
      "--set inner_angles=[0,90] --set rates=[60] --set revolutions=1";
  const std::string six = "six-position --set capture_s=5";
  const std::string ladder = "rate-ladder --set rates=[60] --set revolutions=1 --set settle_s=1";
  for (const auto& [procedure, db] :
       {std::pair{thermal, "thermal"}, std::pair{six, "six"}, std::pair{ladder, "ladder"}}) {
    ASSERT_EQ(run_procedure(procedure, sim, dir_ + name + "-" + db + "-inproc.db").exit_code, 0);
  }

  const std::string lab = dir_ + name + "-lab.json";
  SimStationProcess station({"--station", sim, "--time-scale", kSetsTimeScale, "--station-out", lab,
                             "--table-protocol", p.table, "--chamber-protocol", p.chamber});
  const json lab_file = json::parse(read_text(lab));
  EXPECT_EQ(lab_file["table"]["backend"], p.table_backend);
  EXPECT_EQ(lab_file["chamber"]["backend"], p.chamber_backend);
  // By hand first, as a lab checks a new controller: the state and a setpoint round trip.
  const auto table = run("device --station " + lab + " table get", dir_ + "stderr.txt");
  ASSERT_EQ(table.exit_code, 0) << read_text(dir_ + "stderr.txt");
  EXPECT_FALSE(json::parse(table.out)["outer"]["fault"].get<bool>()) << table.out;
  const auto chamber =
      run("device --station " + lab + " chamber set 27 --ramp 5", dir_ + "stderr.txt");
  ASSERT_EQ(chamber.exit_code, 0) << read_text(dir_ + "stderr.txt");
  EXPECT_NEAR(json::parse(chamber.out)["setpoint_c"].get<double>(), 27.0, 0.05) << chamber.out;

  const std::string gyro =
      "--sensor gyro --model gyro_bias,gyro_scale,gyro_misalignment,earth_rate";
  const std::string accel = "--sensor accel --model accel_bias,accel_scale,accel_misalignment";
  for (const auto& [procedure, db, model] :
       {std::tuple{thermal, "thermal", gyro}, std::tuple{six, "six", accel},
        std::tuple{ladder, "ladder", gyro}}) {
    SCOPED_TRACE(procedure);
    const std::string real_db = dir_ + name + "-" + db + "-real.db";
    const auto r = run_procedure(procedure, lab, real_db);
    ASSERT_EQ(r.exit_code, 0) << procedure << "\n" << r.out;
    calstand::testing::expect_same_quality(fit_json(dir_ + name + "-" + db + "-inproc.db", model),
                                           fit_json(real_db, model), 4.0);
    const std::string events = events_text(real_db);
    EXPECT_EQ(events.find("link lost"), std::string::npos) << events;
    EXPECT_EQ(events.find("bad reply"), std::string::npos) << events;
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, CommandSetStations,
                         ::testing::Values(SetPair{"acutrol3000", "espec", "acutrol", "espec"},
                                           SetPair{"aerosmith", "simserv", "aerosmith", "simserv"},
                                           SetPair{"actidyn", "thermotron", "actidyn",
                                                   "thermotron"},
                                           SetPair{"aerotech", "csz-ezt570", "aerotech", "modbus"}),
                         // not `info`: the macro's own parameter (-Wshadow)
                         [](const auto& param_info) {
                           std::string n =
                               std::string(param_info.param.table) + "_" + param_info.param.chamber;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace

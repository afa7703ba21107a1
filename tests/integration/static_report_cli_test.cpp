// calstand report on a record at rest (issue 32): a simulated ADIS16488-class unit lying on the
// bench (every noise process of its sheet: white, bias instability, Gauss-Markov, random walk),
// written as a calstand-import/2 folder and, by the tests' own MCAP writer
// (tests/support/write_recordings.py), as the MCAP file a ROS 2 recorder would have made. Both
// imports get the noise page, whose figures are those `calstand noise --json` and
// `calstand noise-id --json` give for the same run, not numbers of the page's own; a hand-held
// session with too few poses gets the same page, saying why it is not calibrated.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::Result;
using calstand::testing::run;

// The text between <section id="ID" and its end.
std::string section(const std::string& html, const std::string& id) {
  const auto start = html.find("<section id=\"" + id + "\"");
  if (start == std::string::npos) return "";
  const auto end = html.find("</section>", start);
  return html.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

// As the page writes a datasheet figure (report_datasheet.hpp): 3 significant digits, plain from
// 0.001 to below 1e6.
std::string datasheet_number(double value) {
  if (value == 0.0) return "0";
  const int magnitude = static_cast<int>(std::floor(std::log10(std::abs(value))));
  if (magnitude < -3 || magnitude >= 6) return fmt::format("{:.3g}", value);
  return fmt::format("{:.{}f}", value, std::max(0, 2 - magnitude));
}

class StaticReportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-static-report-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    db_ = dir_ + "static.db";
    // 12 min at 100 Hz: longer than the 10 min a stability figure needs, short enough for CI.
    Result r =
        run("sim-session --kind static --model adis16488 --seed 11 --rate 100 --rest 720 "
            "--out " +
            dir_ + "rest");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const std::string mcap = "/usr/bin/python3 " + std::string(CALSTAND_SOURCE_DIR) +
                             "/tests/support/write_recordings.py --from-csv " + dir_ + "rest " +
                             dir_ + "rest.mcap";
    ASSERT_EQ(std::system(mcap.c_str()), 0) << mcap;
    const auto site = nlohmann::json::parse(read_text(dir_ + "rest/meta.json")).at("site");
    r = run("import " + dir_ + "rest --db " + db_, "/dev/null");  // run 1
    ASSERT_EQ(r.exit_code, 0) << r.out;
    r = run("import " + dir_ + "rest.mcap --db " + db_ + " --latitude " +
                site.at("latitude_deg").dump() + " --height " + site.at("height_m").dump() +
                " --gravity " + site.at("gravity_mps2").dump(),
            "/dev/null");  // run 2
    ASSERT_EQ(r.exit_code, 0) << r.out;
    // Run 3: a hand-held session of 3 poses after a 10 min rest: too few to calibrate.
    r =
        run("sim-session --kind hand --model adis16488 --seed 12 --rate 100 --poses 3 --rest 620 "
            "--out " +
            dir_ + "hand");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    r = run("import " + dir_ + "hand --db " + db_, "/dev/null");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    // The composite models (GMWM, seconds a channel) on run 1 only: the others check the rest.
    for (int id = 1; id <= 3; ++id) {
      reports_[id] = run(fmt::format("report --db {} --run {} --out {}run{}.html{}", db_, id, dir_,
                                     id, id == 1 ? "" : " --no-noise-model"),
                         dir_ + "report.err");
    }
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static nlohmann::json json_of(const std::string& args) {
    const Result r = run(args + " --db " + db_ + " --json", "/dev/null");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.out;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  }

  // Every noise figure of `calstand noise --json` for `run` stands in the page's table, as the
  // page writes it (value +- sigma, or the value alone where it has no sigma; '-' unresolved).
  static void expect_noise_figures(int run_id) {
    const std::string html = read_text(fmt::format("{}run{}.html", dir_, run_id));
    const std::string allan = section(html, "allan");
    ASSERT_FALSE(allan.empty()) << "no Allan section on the page of run " << run_id;
    const nlohmann::json noise = json_of(fmt::format("noise --run {} --no-noise-model", run_id));
    ASSERT_EQ(noise.at("channels").size(), 6u);
    int checked = 0;
    for (const auto& ch : noise.at("channels")) {
      for (const auto& f : ch.at("figures")) {
        if (!f.at("resolved").get<bool>()) continue;
        const double v = f.at("value").get<double>();
        const std::string cell = f.at("sigma").is_null() ? fmt::format(">{:.3g}</td>", v)
                                                         : fmt::format(">{:.3g} ± {:.2g}</td>", v,
                                                                       f.at("sigma").get<double>());
        EXPECT_NE(allan.find(cell), std::string::npos)
            << "run " << run_id << " " << ch.at("channel") << " " << f.at("name") << " " << cell;
        ++checked;
      }
    }
    EXPECT_GE(checked, 18) << "N, the Allan minimum and B at least, on every channel";
    // The record-length advice of the same record.
    const std::string advice = section(html, "record-length");
    const nlohmann::json needs = noise.at("record_length");
    for (const char* sensor : {"gyro", "accel"}) {
      for (const auto& [figure, need] : needs.at(sensor).items()) {
        EXPECT_NE(advice.find(fmt::format(">{:.3g}</td>", need.at("tau_s").get<double>())),
                  std::string::npos)
            << sensor << " " << figure;
      }
    }
  }

  static inline std::string dir_, db_;
  static inline Result reports_[4];
};

TEST_F(StaticReportCli, AnImportedRecordAtRestGetsItsNoisePage) {
  ASSERT_EQ(reports_[1].exit_code, 0) << reports_[1].out;
  EXPECT_NE(reports_[1].out.find("a record at rest, no calibration"), std::string::npos)
      << reports_[1].out;
  const std::string html = read_text(dir_ + "run1.html");
  for (const char* id :
       {"calibration", "record", "allan", "record-length", "noise-model", "datasheet-stability"}) {
    EXPECT_FALSE(section(html, id).empty()) << id;
  }
  EXPECT_NE(section(html, "calibration").find("lies at rest throughout"), std::string::npos);
  // Two Allan plots (gyros, accelerometers) with their intervals (error bars).
  EXPECT_NE(section(html, "allan").find("allan-gyro"), std::string::npos);
  EXPECT_NE(section(html, "allan").find("allan-accel"), std::string::npos);
  // The site the import recorded, and each figure's estimator.
  EXPECT_NE(html.find("Site: latitude"), std::string::npos);
  EXPECT_NE(section(html, "allan").find("IEEE Std 952 model fitted"), std::string::npos);
  expect_noise_figures(1);
}

TEST_F(StaticReportCli, TheSameRecordFromMcapGivesTheSamePage) {
  ASSERT_EQ(reports_[2].exit_code, 0) << reports_[2].out;
  expect_noise_figures(2);
  const std::string csv = section(read_text(dir_ + "run1.html"), "allan");
  const std::string mcap = section(read_text(dir_ + "run2.html"), "allan");
  // The tables (the plots' titles name their runs' steps alike): the same samples, the same
  // figures.
  EXPECT_EQ(csv.substr(csv.find("<h3>")), mcap.substr(mcap.find("<h3>")));
  EXPECT_NE(read_text(dir_ + "run2.html").find("Source: mcap"), std::string::npos);
}

TEST_F(StaticReportCli, TheCompositeModelIsNoiseIdsOnTheSameRecord) {
  ASSERT_EQ(reports_[1].exit_code, 0) << reports_[1].out;
  const std::string model = section(read_text(dir_ + "run1.html"), "noise-model");
  for (const char* channel : {"gx", "az"}) {
    // The page leaves out the scales under `calstand noise`'s shortest averaging time, 20
    // sample periods (0.2 s at 100 Hz).
    const nlohmann::json id =
        json_of(fmt::format("noise-id --run 1 --channel {} --min-tau 0.2", channel));
    ASSERT_FALSE(id.at("terms").empty()) << channel;
    for (const auto& term : id.at("terms")) {
      for (const auto& [name, p] : term.at("parameters").items()) {
        const std::string cell = fmt::format(">{:.4g}</td>", p.at("value").get<double>());
        EXPECT_NE(model.find(cell), std::string::npos) << channel << " " << name << " " << cell;
      }
    }
  }
}

TEST_F(StaticReportCli, TheStabilityIsAnalyzeStabilitysOnTheSameRecord) {
  ASSERT_EQ(reports_[1].exit_code, 0) << reports_[1].out;
  const std::string stability = section(read_text(dir_ + "run1.html"), "datasheet-stability");
  const nlohmann::json a = json_of("analyze stability --no-noise-model --run 1");
  const nlohmann::json& s = a.contains("analyses") ? a.at("analyses").at("stability") : a;
  ASSERT_TRUE(s.contains("gyro")) << a.dump();
  for (const char* sensor : {"gyro", "accel"}) {
    const std::string key =
        std::string("bias_instability_") + (sensor[0] == 'g' ? "deg_per_h" : "ug");
    for (const auto& v : s.at(sensor).at(key)) {
      // A bound ("&lt; 5.53") where the curve has not turned up yet: the number ends the cell.
      EXPECT_NE(stability.find(datasheet_number(v.get<double>()) + "</td>"), std::string::npos)
          << sensor << " " << v;
    }
  }
}

// As the full report (and `calstand certificate`): --out FILE.pdf prints the page to PDF.
TEST_F(StaticReportCli, APdfPathPrintsThePage) {
  if (std::system("command -v chromium >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "chromium is not installed (scripts/setup-deps.sh installs it)";
  }
  const std::string pdf = dir_ + "run2.pdf";
  const Result r = run("report --db " + db_ + " --run 2 --no-noise-model --out " + pdf);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string bytes = read_text(pdf);
  EXPECT_EQ(bytes.rfind("%PDF-", 0), 0u);
  EXPECT_GT(bytes.size(), 20000u) << "the plots are in it";
}

TEST_F(StaticReportCli, ARunWithTooFewPosesSaysSoAndShowsTheNoiseOfItsRest) {
  ASSERT_EQ(reports_[3].exit_code, 0) << reports_[3].out;
  const std::string html = read_text(dir_ + "run3.html");
  const std::string calibration = section(html, "calibration");
  EXPECT_NE(calibration.find("static poses are needed"), std::string::npos) << calibration;
  EXPECT_NE(calibration.find("found"), std::string::npos) << calibration;
  EXPECT_NE(section(html, "record").find("the initial rest"), std::string::npos)
      << section(html, "record");
  EXPECT_FALSE(section(html, "allan").empty());
}

}  // namespace

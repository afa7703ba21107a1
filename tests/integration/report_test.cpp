// calstand report end to end: a short campaign recorded on the simulator, two fits with a
// growing model, then the report, rendered in headless Chromium: every section is there with
// plots that hold plotted paths, the screenshot is not blank, and the page loads nothing from
// outside. A long static run adds the Allan deviation; a missing gnuplot is a clear error.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::Result;
using calstand::testing::run;
using calstand::testing::write_text;

// Runs a shell command line; stdout only unless the command redirects stderr itself.
Result shell(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

std::string find_chromium() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
      const auto candidate = std::filesystem::path(dir) / name;
      if (!dir.empty() && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
  }
  return "";
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// Width and height of a PNG from its IHDR chunk (0, 0 when it is not a PNG).
std::pair<std::uint32_t, std::uint32_t> png_size(const std::string& png) {
  if (png.size() < 24 || png.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) return {0, 0};
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(png[at + i]);
    return v;
  };
  return {be32(16), be32(20)};
}

constexpr const char* kStation =
    R"({"format": "calstand-station/1", "name": "report-test", "seed": 5,
  "site": {"latitude_deg": 30.5, "height_m": 25},
  "table": {"backend": "sim", "outer_axis": [0, 1, 0], "inner_axis": [0, 0, 1],
            "outer": {"max_rate_dps": 400, "max_accel_dps2": 300},
            "inner": {"max_rate_dps": 1000, "max_accel_dps2": 500}},
  "chamber": {"backend": "sim", "min_c": -55, "max_c": 125, "max_ramp_c_per_min": 5},
  "imus": [{"name": "imu0", "backend": "sim", "truth": {"format": "calstand-truth/1",
    "parameters": {"gyro_bias.x": 0.002, "gyro_bias.y": -0.001, "gyro_bias.z": 0.003,
      "gyro_scale.x": 300, "gyro_scale.y": -200, "gyro_scale.z": 150,
      "accel_bias.x": 0.01, "accel_bias.y": -0.02, "accel_bias.z": 0.005,
      "accel_scale.x": -400, "accel_scale.y": 250, "accel_scale.z": 100,
      "accel_misalignment.yx": 0.0004, "accel_misalignment.xz": -0.0002},
    "noise": {"gyro": {"arw_deg_per_sqrt_h": 0.1}, "accel": {"vrw_mps_per_sqrt_h": 0.03}},
    "output": {"sample_rate_hz": 200}}}]})";

class ReportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-report-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_ + "home");
    write_text(dir_ + "station.json", kStation);
    db_ = dir_ + "report.db";
    // Run 1: six positions (short captures); run 2: a 10 min static record.
    for (const std::string args :
         {"six-position --set capture_s=20",
          "static-allan --set duration_s=600 --set soak_s=1 --set warmup_s=1"}) {
      const auto r =
          run("run " + args + " --station " + dir_ + "station.json --db " + db_ + " --quiet");
      ASSERT_EQ(r.exit_code, 0) << r.out;
    }
    // The error falls as the model grows: biases only, then the default classical model.
    for (const std::string model :
         {"gyro_bias,accel_bias", "gyro_bias,earth_rate,accel_bias,accel_scale"}) {
      const auto r = run("fit --db " + db_ + " --run 1 --model " + model);
      ASSERT_EQ(r.exit_code, 0) << r.out;
    }
    report_ = run("report --db " + db_ + " --run 1 --out " + dir_ + "run1.html");
    static_report_ = run("report --db " + db_ +
                         " --run 2 --model gyro_bias --no-noise-model --out " + dir_ + "run2.html");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // Chromium's view of a page: the DOM after load and a 1200 x 3000 screenshot.
  static Result chromium(const std::string& args) {
    return shell("HOME=" + dir_ + "home timeout 90 " + chromium_ +
                 " --headless --no-sandbox --disable-gpu --disable-dev-shm-usage "
                 "--no-first-run --hide-scrollbars --user-data-dir=" +
                 dir_ + "home/profile " + args + " 2>" + dir_ + "chromium.err");
  }

  void SetUp() override {
    ASSERT_EQ(report_.exit_code, 0) << report_.out;
    if (chromium_.empty()) chromium_ = find_chromium();
  }

  static inline std::string dir_, db_, chromium_;
  static inline Result report_, static_report_;
};

TEST_F(ReportCli, PageLoadsNothingFromOutside) {
  const std::string html = read_text(dir_ + "run1.html");
  ASSERT_GT(html.size(), 10000u);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("@import"), std::string::npos);
  EXPECT_EQ(html.find(" src="), std::string::npos);
  // Every reference stays inside the page.
  const std::regex ref(R"((href=|url\()['"]?([^'" )]*))");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), ref); it != std::sregex_iterator();
       ++it) {
    EXPECT_TRUE((*it)[2].str().starts_with("#")) << (*it)[0].str();
  }
}

TEST_F(ReportCli, HistoryKeepsTheFitsAndTheReport) {
  const auto r = run("history --db " + db_ + " --run 1 --json", dir_ + "stderr.txt");
  ASSERT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
  const auto fits = nlohmann::json::parse(r.out);
  ASSERT_GE(fits.size(), 3u) << fits.dump(2);
  EXPECT_EQ(fits[2]["command"], "report");
  // The error falls: biases only fit worse than the classical model of the report.
  EXPECT_GT(fits[0]["chi2_dof"].get<double>(), fits[2]["chi2_dof"].get<double>());
  const std::string html = read_text(dir_ + "run1.html");
  EXPECT_NE(html.find("+earth_rate"), std::string::npos) << "the added terms label the fits";
}

TEST_F(ReportCli, ChromiumRendersEverySectionWithPlots) {
  if (chromium_.empty())
    GTEST_SKIP() << "chromium is not installed (scripts/setup-deps.sh installs it)";
  const auto dom = chromium("--dump-dom file://" + dir_ + "run1.html");
  ASSERT_EQ(dom.exit_code, 0) << read_text(dir_ + "chromium.err");
  for (const char* id : {"history", "residuals", "signals", "parameters", "candidates", "allan"}) {
    EXPECT_NE(dom.out.find(std::string("<section id=\"") + id + "\""), std::string::npos) << id;
  }
  // History, residuals, at least one signal and the candidates: each an SVG with plotted paths.
  EXPECT_GE(count(dom.out, "<svg"), 4u);
  std::size_t plotted = 0;
  for (auto pos = dom.out.find("<svg"); pos != std::string::npos;
       pos = dom.out.find("<svg", pos + 1)) {
    const std::string svg = dom.out.substr(pos, dom.out.find("</svg>", pos) - pos);
    if (count(svg, "<path") >= 5 && svg.find(" d=\"M") != std::string::npos) ++plotted;
  }
  EXPECT_GE(plotted, 4u);
  EXPECT_NE(dom.out.find("gyro_bias.x"), std::string::npos) << "the parameter table";
  EXPECT_NE(dom.out.find("class=\"advice"), std::string::npos) << "the diagnosis' advice";
}

TEST_F(ReportCli, ScreenshotIsNotBlank) {
  if (chromium_.empty())
    GTEST_SKIP() << "chromium is not installed (scripts/setup-deps.sh installs it)";
  write_text(dir_ + "blank.html", "<!DOCTYPE html><html><body></body></html>");
  const auto blank = chromium("--window-size=1200,3000 --screenshot=" + dir_ + "blank.png file://" +
                              dir_ + "blank.html");
  const auto shot = chromium("--window-size=1200,3000 --screenshot=" + dir_ + "run1.png file://" +
                             dir_ + "run1.html");
  ASSERT_EQ(shot.exit_code, 0) << read_text(dir_ + "chromium.err");
  const std::string png = read_text(dir_ + "run1.png");
  const auto [width, height] = png_size(png);
  EXPECT_EQ(width, 1200u);
  EXPECT_EQ(height, 3000u);
  // Plots, text and tables compress far worse than an empty page.
  EXPECT_GT(png.size(), 100u * 1024u);
  EXPECT_GT(png.size(), 5u * read_text(dir_ + "blank.png").size());
}

TEST_F(ReportCli, StaticRunShowsTheAllanDeviationWithItsNoiseLines) {
  ASSERT_EQ(static_report_.exit_code, 0) << static_report_.out;
  const std::string html = read_text(dir_ + "run2.html");
  const auto at = html.find("<section id=\"allan\">");
  ASSERT_NE(at, std::string::npos) << "no Allan section: " << static_report_.out;
  const std::string allan = html.substr(at, html.find("</section>", at) - at);
  EXPECT_EQ(count(allan, "<svg"), 2u) << "gyro and accelerometer";
  EXPECT_NE(allan.find("N random walk"), std::string::npos) << "the fitted white-noise line";
  EXPECT_NE(allan.find("angle random walk"), std::string::npos) << "the datasheet figures";
  // A static run without an error model: what the record is long enough for, as the page of a
  // record at rest has it; the composite models were left out (--no-noise-model).
  EXPECT_NE(html.find("<section id=\"record-length\">"), std::string::npos);
  EXPECT_NE(html.find("not asked for (--no-noise-model)"), std::string::npos);
  // The six-position run is not static: its page says why there is no Allan deviation.
  EXPECT_NE(read_text(dir_ + "run1.html").find("not a static run"), std::string::npos);
}

TEST_F(ReportCli, MissingGnuplotIsAClearError) {
  const auto r = shell("env PATH=/nonexistent " + std::string(CALSTAND_BIN) + " report --db " +
                       db_ + " --run 1 --out " + dir_ + "none.html 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("gnuplot"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "none.html"));
  // A gnuplot that fails: its message is passed on.
  std::filesystem::create_directories(dir_ + "bin");
  write_text(dir_ + "bin/gnuplot", "#!/bin/sh\necho 'unknown terminal type' >&2\nexit 1\n");
  std::filesystem::permissions(dir_ + "bin/gnuplot", std::filesystem::perms::owner_all);
  const auto failed = shell("env PATH=" + dir_ + "bin:/usr/bin:/bin " + std::string(CALSTAND_BIN) +
                            " report --db " + db_ + " --run 1 --out " + dir_ + "none.html 2>&1");
  EXPECT_EQ(failed.exit_code, 2) << failed.out;
  EXPECT_NE(failed.out.find("gnuplot"), std::string::npos) << failed.out;
  EXPECT_NE(failed.out.find("unknown terminal type"), std::string::npos) << failed.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "none.html"));
}

}  // namespace

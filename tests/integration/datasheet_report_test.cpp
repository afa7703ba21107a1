// calstand report's datasheet figures: each procedure of the test catalogue runs in process on
// the simulated station (reduced to a second or two of simulation), its report is rendered, and
// the page holds the section of each analysis that applies with the numbers that analysis gives
// when called on its own (formatted as the page formats them), and no section of one that does
// not apply. A run without an error model (repeatability, warm-up, a long static record) gets a
// page of its figures instead of an error, and nothing is added to its fit history; a
// calibration run keeps its fit. A figure the run should have but the analysis refuses is
// named with the analysis's reason; a bad request is still an error.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.hpp"
#include "datasheet/bandwidth.hpp"
#include "datasheet/hysteresis.hpp"
#include "datasheet/repeatability.hpp"
#include "datasheet/stability.hpp"
#include "datasheet/warmup.hpp"
#include "in_process_run.hpp"
#include "report/report_data.hpp"
#include "report/report_datasheet.hpp"
#include "report/report_html.hpp"
#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"

namespace calstand {
namespace {

using analysis::datasheet_number;
using testing::fresh_db;
using testing::remove_db;
using testing::run_procedure;

/// One rendered report of a fresh run of a library procedure.
struct Rendered {
  std::string db_path;
  std::int64_t run = 0;
  analysis::ReportData data;
  std::string html;
};

Rendered render(const std::string& procedure, const std::vector<std::string>& overrides,
                const core::StationConfig& station = sim::default_station()) {
  Rendered r;
  r.db_path = fresh_db(procedure);
  r.run = run_procedure(procedure, overrides, r.db_path, station);
  store::Database db(r.db_path);
  analysis::ReportRequest request;
  request.db = r.db_path;
  request.run = r.run;
  // The composite noise models of a static run (GMWM, seconds a channel) are the static report
  // tests' (report_data_test.cpp, static_report_cli_test.cpp); not needed for these figures.
  request.noise_model = false;
  r.data = analysis::gather_report(db, request);
  r.html = analysis::render_report_html(r.data);
  return r;
}

/// The section with id `id`, "" when the page has none.
std::string section(const std::string& html, const std::string& id) {
  const auto at = html.find("<section id=\"" + id + "\"");
  if (at == std::string::npos) return "";
  return html.substr(at, html.find("</section>", at) - at);
}

bool has_section(const std::string& html, const std::string& id) {
  return !section(html, id).empty();
}

std::string cell(const std::string& markup) { return "<td class=\"num\">" + markup + "</td>"; }
std::string interval(double lo, double hi) {
  return datasheet_number(lo) + " &ndash; " + datasheet_number(hi);
}

const std::vector<std::string> kFitSections = {"history", "residuals", "signals", "parameters",
                                               "candidates"};
const std::vector<std::string> kFigureSections = {"datasheet-repeatability", "datasheet-warmup",
                                                  "datasheet-stability", "datasheet-hysteresis",
                                                  "datasheet-bandwidth"};

// Every figure section but `shown` is absent.
void expect_only_figure(const std::string& html, const std::string& shown) {
  for (const auto& id : kFigureSections) {
    EXPECT_EQ(has_section(html, id), id == shown) << id;
  }
}

TEST(DatasheetReport, RepeatabilityRunRendersItsFiguresWithoutAFit) {
  const Rendered r = render("repeatability", {"cycles=4", "off_s=5", "settle_s=30", "capture_s=20",
                                              "rates=[200]", "revolutions=1"});
  if (::testing::Test::HasFailure()) return;
  EXPECT_FALSE(r.data.fitted());
  EXPECT_NE(r.data.no_fit_reason.find("switched off and on between its recorded steps"),
            std::string::npos)
      << r.data.no_fit_reason;
  for (const auto& id : kFitSections) EXPECT_FALSE(has_section(r.html, id)) << id;
  EXPECT_NE(section(r.html, "model").find("Not fitted"), std::string::npos);
  // The run's summary: per cycle three moves, power off and on, a capture and six turns.
  EXPECT_NE(r.html.find("48/48 steps (12 move, 8 power, 4 capture, 24 rate)"), std::string::npos);
  expect_only_figure(r.html, "datasheet-repeatability");

  store::Database db(r.db_path);
  EXPECT_TRUE(store::fit_history(db, r.run).empty()) << "no fit recorded for a page without one";
  const analysis::RepeatabilityAnalysis a = analysis::analyse_repeatability(db, r.run, "");
  const std::string s = section(r.html, "datasheet-repeatability");
  EXPECT_NE(s.find("over 4 power cycles"), std::string::npos);
  for (const auto& ch : a.channels) {
    EXPECT_NE(s.find(cell(datasheet_number(ch.repeatability))), std::string::npos) << ch.channel;
    EXPECT_NE(s.find(cell(interval(ch.repeatability_lo, ch.repeatability_hi))), std::string::npos)
        << ch.channel;
    EXPECT_NE(s.find(cell(datasheet_number(ch.noise_of_means))), std::string::npos) << ch.channel;
  }
  for (const auto& axis : a.gyro_scale) {
    ASSERT_TRUE(axis.measured);
    EXPECT_NE(s.find(cell(datasheet_number(axis.repeatability_ppm))), std::string::npos);
    EXPECT_NE(s.find(cell(interval(axis.repeatability_lo_ppm, axis.repeatability_hi_ppm))),
              std::string::npos);
  }
  EXPECT_NE(s.find("<svg"), std::string::npos) << "the turn-on bias of each cycle";
  // The overview says what the others lack.
  EXPECT_NE(section(r.html, "datasheet").find("no oscillate step"), std::string::npos);
  remove_db(r.db_path);
}

// A unit with a power-on transient (gyro 20, -15, 10 deg/h settling with 60 s).
TEST(DatasheetReport, WarmUpRunShowsTheTransientFitAgainstTheData) {
  core::StationConfig station = sim::default_station();
  sim::ImuTruth truth = sim::resolve_imu_truth(station.imus[0], station.seed, 0);
  truth.gyro_power_on_bias = Eigen::Vector3d(20.0, -15.0, 10.0) / 3600.0;
  truth.power_on_time_constant_s = 60.0;
  station.imus[0].model.clear();
  station.imus[0].truth = sim::imu_truth_to_json(truth);
  const Rendered r = render("warm-up", {"off_s=60", "capture_s=600"}, station);
  if (::testing::Test::HasFailure()) return;
  EXPECT_FALSE(r.data.fitted());
  for (const auto& id : kFitSections) EXPECT_FALSE(has_section(r.html, id)) << id;
  expect_only_figure(r.html, "datasheet-warmup");

  store::Database db(r.db_path);
  const analysis::WarmupAnalysis w = analysis::analyse_warmup(
      db, r.run, "", std::nullopt, analysis::DatasheetOptions{}.warmup_band_deg_per_h,
      analysis::DatasheetOptions{}.warmup_band_ug);
  const std::string s = section(r.html, "datasheet-warmup");
  int resolved = 0;
  for (const auto& ch : w.channels) {
    EXPECT_NE(s.find(cell(datasheet_number(ch.amplitude) + " &plusmn; " +
                          datasheet_number(ch.amplitude_sigma, 2))),
              std::string::npos)
        << ch.channel;
    if (!ch.resolved) continue;
    ++resolved;
    EXPECT_NE(s.find(cell(datasheet_number(ch.time_constant_s))), std::string::npos) << ch.channel;
  }
  EXPECT_GE(resolved, 3) << "the gyro transients stand far above the noise";
  EXPECT_NE(s.find("fit: tau"), std::string::npos) << "the fitted curve is drawn";
  // The record starts at power-up: it is not taken for in-run stability.
  EXPECT_NE(section(r.html, "datasheet").find("warm-up instead"), std::string::npos);
  remove_db(r.db_path);
}

TEST(DatasheetReport, StaticRecordShowsStabilityBesideTheAllanDeviationWithoutAFit) {
  const Rendered r = render("static-allan", {"duration_s=700", "soak_s=1", "warmup_s=1"});
  if (::testing::Test::HasFailure()) return;
  EXPECT_FALSE(r.data.fitted());
  expect_only_figure(r.html, "datasheet-stability");
  EXPECT_TRUE(has_section(r.html, "allan"));
  EXPECT_NE(section(r.html, "allan").find("<svg"), std::string::npos);

  store::Database db(r.db_path);
  const analysis::StabilityAnalysis a = analysis::analyse_stability(db, r.run, "", std::nullopt);
  const std::string s = section(r.html, "datasheet-stability");
  for (const auto& ch : a.channels) {
    const std::string bound = ch.floor_resolved ? "" : "&lt; ";
    EXPECT_NE(s.find(cell(bound + datasheet_number(ch.bias_instability))), std::string::npos)
        << ch.channel;
    EXPECT_NE(s.find(cell(interval(ch.bias_instability_lo, ch.bias_instability_hi))),
              std::string::npos)
        << ch.channel;
    // The chosen bias model, and the bias variation only where it is Gauss-Markov.
    EXPECT_NE(s.find(">" + std::string(solver::to_string(ch.bias_model)) + "</td>"),
              std::string::npos)
        << ch.channel;
    EXPECT_EQ(ch.variation_sigma.has_value(), ch.bias_model == solver::BiasModel::kGaussMarkov);
    if (ch.variation_sigma) {
      EXPECT_NE(s.find(cell(datasheet_number(*ch.variation_sigma))), std::string::npos)
          << ch.channel;
    }
  }
  remove_db(r.db_path);
}

TEST(DatasheetReport, HysteresisRunKeepsItsFitAndShowsUpAgainstDownInDatasheetUnits) {
  const Rendered r =
      render("thermal-hysteresis",
             {"soak_s=60", "capture_s=10", "temperatures=[10,40,70]", "temperatures_down=[40,10]"});
  if (::testing::Test::HasFailure()) return;
  EXPECT_TRUE(r.data.fitted()) << r.data.no_fit_reason;
  for (const auto& id : kFitSections) EXPECT_TRUE(has_section(r.html, id)) << id;
  expect_only_figure(r.html, "datasheet-hysteresis");

  store::Database db(r.db_path);
  const analysis::HysteresisAnalysis h = analysis::analyse_hysteresis(db, r.run, "");
  ASSERT_FALSE(h.points.empty());
  const std::string s = section(r.html, "datasheet-hysteresis");
  for (const auto& p : h.points) {
    // Gyro biases in deg/h and accelerometer biases in ug, as a datasheet states them.
    const double k = p.unit == "deg/s" ? 3600.0 : p.unit == "m/s^2" ? 1e6 / 9.80665 : 1.0;
    const std::string unit = p.unit == "deg/s" ? "deg/h" : p.unit == "m/s^2" ? "ug" : p.unit;
    const std::string difference = datasheet_number(k * p.difference) + " &plusmn; " +
                                   datasheet_number(k * p.difference_sigma, 2);
    const auto at =
        s.find("<td>" + p.parameter + "</td>", s.find(cell(fmt::format("{:g}", p.temperature_c))));
    ASSERT_NE(at, std::string::npos) << p.parameter << " at " << p.temperature_c;
    const std::string line = s.substr(at, s.find("</tr>", at) - at);
    EXPECT_NE(line.find(cell(datasheet_number(k * p.up, 4) + " &plusmn; " +
                             datasheet_number(k * p.up_sigma, 2))),
              std::string::npos)
        << line;
    EXPECT_NE(line.find(difference), std::string::npos) << line;
    EXPECT_NE(line.find("<td>" + unit + "</td>"), std::string::npos) << line;
  }
  EXPECT_NE(s.find("<svg"), std::string::npos);
  remove_db(r.db_path);
}

TEST(DatasheetReport, BandwidthRunShowsTheGainCurveAndEachAxisBandwidthAndDelay) {
  const Rendered r = render("bandwidth", {"frequencies_hz=[1,5,10,20]", "cycles=10"});
  if (::testing::Test::HasFailure()) return;
  expect_only_figure(r.html, "datasheet-bandwidth");
  store::Database db(r.db_path);
  const analysis::BandwidthAnalysis b = analysis::analyse_bandwidth(db, r.run, "");
  const std::string s = section(r.html, "datasheet-bandwidth");
  for (std::size_t axis = 0; axis < 3; ++axis) {
    ASSERT_TRUE(b.delay_s[axis]);
    EXPECT_NE(s.find(cell(datasheet_number(*b.delay_s[axis] * 1e3))), std::string::npos) << axis;
    ASSERT_TRUE(b.delay_interval_s[axis]) << axis;
    EXPECT_NE(s.find(cell(interval((*b.delay_interval_s[axis])[0] * 1e3,
                                   (*b.delay_interval_s[axis])[1] * 1e3))),
              std::string::npos)
        << axis;
    if (b.bandwidth_hz[axis]) {
      EXPECT_NE(s.find(cell(datasheet_number(*b.bandwidth_hz[axis], 4))), std::string::npos)
          << axis;
      if (b.bandwidth_interval_hz[axis]) {
        const auto& ci = *b.bandwidth_interval_hz[axis];
        EXPECT_NE(s.find(cell(interval(ci[0], ci[1]))), std::string::npos) << axis;
      }
    }
  }
  for (const auto& p : b.points) {
    EXPECT_NE(s.find(cell(fmt::format("{:.4f}", p.gain))), std::string::npos) << p.label;
  }
  EXPECT_NE(s.find("bandwidth-gain"), std::string::npos) << "the gain curve";
  remove_db(r.db_path);
}

TEST(DatasheetReport, CalibrationRunKeepsItsReportAndSaysNoFigureApplies) {
  const Rendered r = render("six-position", {"capture_s=10"});
  if (::testing::Test::HasFailure()) return;
  EXPECT_TRUE(r.data.fitted()) << r.data.no_fit_reason;
  for (const auto& id : kFitSections) EXPECT_TRUE(has_section(r.html, id)) << id;
  expect_only_figure(r.html, "");
  EXPECT_NE(section(r.html, "datasheet").find("None of the test catalogue"), std::string::npos);
  remove_db(r.db_path);
}

// A warm-up shorter than the analysis's minimum: the run has a record from power-up, so the
// page must say why its warm-up figures are missing, in the analysis's words.
TEST(DatasheetReport, AFigureTheRunShouldHaveButTheAnalysisRefusesIsNamedWithWhy) {
  const Rendered r = render("warm-up", {"off_s=10", "capture_s=30"});
  if (::testing::Test::HasFailure()) return;
  EXPECT_FALSE(has_section(r.html, "datasheet-warmup"));
  const std::string overview = section(r.html, "datasheet");
  EXPECT_NE(overview.find("missing"), std::string::npos) << overview;
  EXPECT_NE(overview.find("a warm-up fit needs at least 60 s"), std::string::npos) << overview;
  // A bad request is no figure's absence: it stays an error.
  store::Database db(r.db_path);
  analysis::ReportRequest request;
  request.db = r.db_path;
  request.run = r.run;
  request.device = "imu9";
  EXPECT_THROW((void)analysis::gather_report(db, request), core::InputError);
  remove_db(r.db_path);
}

}  // namespace
}  // namespace calstand

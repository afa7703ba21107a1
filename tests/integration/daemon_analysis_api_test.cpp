// The loop API of calstandd (issue 14) against a daemon in-process on an ephemeral loopback
// port with the simulated station: a fit or diagnosis over the API is exactly `calstand fit
// --json` / `diagnose --json` on the same run, the token is required for POSTs, bad requests
// name the field, and the series downsampling keeps its bounds.
#include <gtest/gtest.h>

#include <algorithm>

#include "cli_runner.hpp"
#include "core/error_terms.hpp"
#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "daemon_test_support.hpp"
#include "in_process_daemon.hpp"
#include "sim/hand_session.hpp"
#include "sim/session_folder.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/import_export.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace {

using namespace calstand;
using calstand::testing::ApiClient;
using calstand::testing::Reply;
using calstand::testing::wait_until;

using calstand::testing::InProcessDaemon;

// One recorded six-position run (5 s captures) in a fresh database, served by a daemon.
class AnalysisApi : public ::testing::Test {
 protected:
  void SetUp() override {
    db_ = calstand::testing::fresh_dir(
              ::testing::UnitTest::GetInstance()->current_test_info()->name()) +
          "/station.db";
    daemon_ = std::make_unique<InProcessDaemon>(db_);
    api_ = std::make_unique<ApiClient>(daemon_->port());
    run_ = api_->submit("six-position", {{"capture_s", 5}});
    ASSERT_GT(run_, 0);
    ASSERT_TRUE(wait_until([&] {
      const Reply r = api_->get(path(""));
      return r.status == 200 && r.body.value("status", "") == "completed";
    }));
  }
  std::string path(const std::string& tail) const { return "/runs/" + std::to_string(run_) + tail; }
  nlohmann::json cli_json(const std::string& args) {
    const auto r = calstand::testing::run(
        args + " --db " + db_ + " --run " + std::to_string(run_) + " --json", "/dev/null");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.out;
    return nlohmann::json::parse(r.out, nullptr, false);
  }

  std::string db_;
  std::unique_ptr<InProcessDaemon> daemon_;
  std::unique_ptr<ApiClient> api_;
  std::int64_t run_ = 0;
};

TEST_F(AnalysisApi, AFitOverTheApiIsTheCommandLinesFitAndIsStoredInTheHistory) {
  const nlohmann::json body = {{"model", {"accel_bias", "accel_scale", "gyro_bias", "earth_rate"}},
                               {"custom", {"k=accel.z:force_z^2"}}};
  const Reply fit = api_->post_json(path("/fits"), body);
  ASSERT_EQ(fit.status, 200) << fit.raw;
  ASSERT_TRUE(fit.body.contains("history_id"));
  const std::int64_t history_id = fit.body["history_id"];
  nlohmann::json from_api = fit.body;
  from_api.erase("history_id");
  const nlohmann::json from_cli = cli_json(
      "fit --model accel_bias,accel_scale,gyro_bias,earth_rate --custom 'k=accel.z:force_z^2'");
  ASSERT_FALSE(from_cli.is_discarded());
  EXPECT_EQ(from_api, from_cli) << "API:\n" << from_api.dump(1) << "\nCLI:\n" << from_cli.dump(1);
  EXPECT_GT(from_api.at("parameters").size(), 6u);

  const Reply history = api_->get(path("/history"));
  ASSERT_EQ(history.status, 200);
  ASSERT_EQ(history.body.size(), 2u);  // the API's fit and the command line's
  EXPECT_EQ(history.body[0]["id"], history_id);
  EXPECT_EQ(history.body[0]["command"], "fit");
  EXPECT_EQ(history.body[0]["custom_terms"], nlohmann::json::array({"k=accel.z:force_z^2"}));
  EXPECT_EQ(history.body, cli_json("history"));
}

TEST_F(AnalysisApi, TheDefaultModelAndADiagnosisAreTheCommandLines) {
  const Reply fit = api_->post(path("/fits"), "");
  ASSERT_EQ(fit.status, 200) << fit.raw;
  nlohmann::json from_api = fit.body;
  from_api.erase("history_id");
  EXPECT_EQ(from_api, cli_json("fit"));

  const nlohmann::json body = {{"model", {"accel_bias", "gyro_bias", "earth_rate"}}};
  const Reply diagnosis = api_->post_json(path("/diagnose"), body);
  ASSERT_EQ(diagnosis.status, 200) << diagnosis.raw;
  EXPECT_TRUE(diagnosis.body.contains("suggestions"));
  EXPECT_TRUE(diagnosis.body.contains("groups"));
  EXPECT_EQ(diagnosis.body, cli_json("diagnose --model accel_bias,gyro_bias,earth_rate"));
}

TEST_F(AnalysisApi, APostWithoutTheTokenIsRefused) {
  const Reply r = api_->post(path("/fits"), "{}", "");
  EXPECT_EQ(r.status, 401);
  EXPECT_EQ(r.body["where"], "Authorization");
  const Reply d = api_->post(path("/diagnose"), "{}", "wrong-token");
  EXPECT_EQ(d.status, 401);
  EXPECT_EQ(api_->get(path("/history")).body.size(), 0u) << "a refused fit was stored";
}

TEST_F(AnalysisApi, BadRequestsNameTheFieldAtFault) {
  const auto where = [&](const std::string& route, const nlohmann::json& body, int status) {
    const Reply r = api_->post_json(route, body);
    EXPECT_EQ(r.status, status) << body.dump() << ": " << r.raw;
    EXPECT_TRUE(r.body.contains("error")) << r.raw;
    return r.body.value("where", "");
  };
  EXPECT_EQ(where(path("/fits"), {{"model", {"gyro_bias", "gyro_bais"}}}, 400), "body.model[1]");
  EXPECT_EQ(where(path("/diagnose"), {{"model", {"gyro_bais"}}}, 400), "body.model[0]");
  EXPECT_EQ(where(path("/fits"), {{"custom", {"k=gyro:force_q"}}}, 400), "body.custom[0]");
  EXPECT_EQ(where(path("/fits"), {{"custom", "k=gyro:force_z"}}, 400), "body.custom");
  EXPECT_EQ(where(path("/fits"), {{"sensor", "all"}}, 400), "body.sensor");
  EXPECT_EQ(where(path("/fits"), {{"modle", {"gyro_bias"}}}, 400), "body.modle");
  EXPECT_EQ(where("/runs/999/fits", nlohmann::json::object(), 404), "/runs/999");
  EXPECT_EQ(api_->get("/runs/999/history").status, 404);

  // A run recorded but not run: nothing to fit.
  std::int64_t empty = 0;
  {
    store::Database db(db_);
    store::NewRun r;
    r.procedure_name = "six-position";
    empty = store::RunStore(db).create_run(r);
  }
  EXPECT_EQ(where("/runs/" + std::to_string(empty) + "/fits", nlohmann::json::object(), 409),
            "run " + std::to_string(empty));
  EXPECT_EQ(api_->get(path("/history")).body.size(), 0u);
}

TEST_F(AnalysisApi, SeriesAreDownsampledWithinTheirBounds) {
  std::int64_t total = 0;
  {
    store::Database db(db_);
    for (const auto& step : store::RunStore(db).load_steps(run_)) {
      total += static_cast<std::int64_t>(store::read_samples(db, run_, step.index, "imu0").size());
    }
  }
  const Reply r = api_->get(path("/series?signal=az&max_points=50"));
  ASSERT_EQ(r.status, 200) << r.raw;
  EXPECT_EQ(r.body["signal"], "az");
  EXPECT_EQ(r.body["unit"], "m/s^2");
  EXPECT_EQ(r.body["samples"], total);
  const auto& t = r.body["t_s"];
  ASSERT_LE(t.size(), 50u);
  ASSERT_GT(t.size(), 25u);
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_LE(r.body["min"][i].get<double>(), r.body["mean"][i].get<double>());
    EXPECT_GE(r.body["max"][i].get<double>(), r.body["mean"][i].get<double>());
    if (i > 0) {
      EXPECT_GT(t[i].get<double>(), t[i - 1].get<double>());
    }
  }
  const Reply window = api_->get(path("/series?signal=temp_c&from_s=2&to_s=4"));
  ASSERT_EQ(window.status, 200) << window.raw;
  EXPECT_LT(window.body["samples"].get<std::int64_t>(), total);
  EXPECT_GE(window.body["t_s"].front().get<double>(), 2.0);
  EXPECT_LE(window.body["t_s"].back().get<double>(), 4.0);

  EXPECT_EQ(api_->get(path("/series?signal=az&max_points=1")).body["where"], "?max_points");
  EXPECT_EQ(api_->get(path("/series?signal=bogus")).body["where"], "?signal");
  EXPECT_EQ(api_->get(path("/series")).body["where"], "?signal");
  EXPECT_EQ(api_->get(path("/series?signal=az&from_s=x")).body["where"], "?from_s");
  EXPECT_EQ(api_->get("/runs/999/series?signal=az").status, 404);
}

TEST_F(AnalysisApi, CatalogueReportAndCalibrationsAreServed) {
  const Reply catalogue = api_->get("/catalogue");
  ASSERT_EQ(catalogue.status, 200);
  EXPECT_EQ(catalogue.body["terms"].size(), core::error_term_catalogue().size());
  EXPECT_FALSE(catalogue.body["signals"].empty());

  const Reply report = api_->get(path("/report"));
  if (report.status == 503) {
    EXPECT_EQ(report.body["where"], "gnuplot");
  } else {
    ASSERT_EQ(report.status, 200) << report.raw.substr(0, 300);
    EXPECT_EQ(report.raw.rfind("<!DOCTYPE html>", 0), 0u);
    bool html = false;
    for (const auto& [k, v] : report.headers)
      html |= k == "Content-Type" && v.starts_with("text/html");
    EXPECT_TRUE(html);
  }

  EXPECT_EQ(api_->get(path("/calibrations")).body.size(), 0u);
  const auto c = calstand::testing::run(
      "calibrate --db " + db_ + " --run " + std::to_string(run_) +
          " --model accel_bias,gyro_bias,earth_rate --json --out " + db_ + ".cal.json",
      "/dev/null");
  ASSERT_EQ(c.exit_code, 0) << c.out;
  const std::int64_t id = nlohmann::json::parse(c.out)["calibrations"][0]["calibration_id"];
  const Reply cals = api_->get(path("/calibrations"));
  ASSERT_EQ(cals.status, 200);
  ASSERT_EQ(cals.body.size(), 1u);
  EXPECT_EQ(cals.body[0]["id"], id);
  EXPECT_EQ(cals.body[0]["imu"], "imu0");
  EXPECT_TRUE(cals.body[0]["chi2_dof"].is_number());
  EXPECT_EQ(api_->get(cals.body[0]["href"].get<std::string>()).status, 200);
}

// An acceptance over the API judges the run's records as `calstand accept --json` does, stores
// the verdict, and refuses a bad specification with every violation, a run without a record
// (409) and an unknown run (404).
TEST_F(AnalysisApi, AnAcceptanceIsTheCommandLinesAndIsStored) {
  const std::string spec =
      R"js({"format": "calstand-acceptance/1", "name": "api", "limits": [
            {"parameter": "accel_bias.*", "max_abs": 0.05, "unit": "m/s^2"},
            {"fit": "chi2_dof", "max": 1000}]})js";
  Reply r = api_->post(path("/acceptance"), spec);
  EXPECT_EQ(r.status, 409) << r.raw;  // nothing calibrated yet
  const auto c = calstand::testing::run("calibrate --db " + db_ + " --run " + std::to_string(run_) +
                                            " --model accel_bias,gyro_bias,earth_rate --out " +
                                            db_ + ".cal.json",
                                        "/dev/null");
  ASSERT_EQ(c.exit_code, 0) << c.out;

  r = api_->post(path("/acceptance"), spec);
  ASSERT_EQ(r.status, 200) << r.raw;
  EXPECT_EQ(r.body.at("verdict"), "pass");
  ASSERT_EQ(r.body.at("units").size(), 1u);
  EXPECT_EQ(r.body.at("units")[0].at("acceptance_id"), 1);
  const std::string file = db_ + ".spec.json";
  calstand::testing::write_text(file, spec);
  const nlohmann::json cli = cli_json("accept --spec " + file);
  EXPECT_EQ(cli.at("units")[0].at("acceptance_id"), 2);
  EXPECT_EQ(cli.at("spec").at("sha256"), r.body.at("spec").at("sha256"));  // the same bytes
  EXPECT_EQ(cli.at("units")[0].at("checks"), r.body.at("units")[0].at("checks"));
  EXPECT_EQ(cli.at("decision_rule"), r.body.at("decision_rule"));

  r = api_->post(path("/acceptance"),
                 R"js({"format": "calstand-acceptance/1", "name": "bad", "limits": [
                      {"parameter": "gyro_bias.*", "max_abs": 18, "unit": "deg/h"},
                      {"parameter": "gyro_bais.*", "max_abs": 1, "unit": "deg/s"}]})js");
  ASSERT_EQ(r.status, 400) << r.raw;
  ASSERT_EQ(r.body.at("violations").size(), 2u) << r.raw;
  EXPECT_EQ(r.body.at("violations")[0].at("path"), "limits[0].unit");
  EXPECT_EQ(r.body.at("violations")[1].at("path"), "limits[1].parameter");
  EXPECT_EQ(api_->post("/runs/999/acceptance", spec).status, 404);
  EXPECT_EQ(api_->post(path("/acceptance?validation_run=x"), spec).status, 400);
  EXPECT_EQ(api_->post(path("/acceptance"), spec, "").status, 401);
}

// A run recorded without a table (a hand-held session imported as calstand-import/2): the
// loop's routes take the table-free methods, the same code as `calstand fit` and `diagnose`.
TEST(AnalysisApiWithoutTable, FitsDiagnosisAndReportOfAHandHeldSession) {
  const std::string dir = calstand::testing::fresh_dir("table-free");
  const std::string db = dir + "/station.db";
  InProcessDaemon daemon(db);
  ApiClient api(daemon.port());
  sim::HandSessionOptions options;
  options.poses = 12;
  options.imu.sample_rate_hz = 200.0;
  sim::write_session_folder(sim::simulate_hand_session(options, 9), dir + "/session", {});
  std::int64_t run = 0;
  {
    store::Database handle(db);
    run = store::import_run(handle, dir + "/session").run;
  }
  const std::string runs = "/runs/" + std::to_string(run);

  const Reply fit = api.post_json(runs + "/fits", {{"model", {"gyro_bias", "gyro_g_sensitivity"}}});
  ASSERT_EQ(fit.status, 200) << fit.raw;
  EXPECT_EQ(fit.body.at("method"), "gravity_norm");
  EXPECT_EQ(fit.body.at("model").back(), "gyro_g_sensitivity");
  EXPECT_TRUE(fit.body.at("chi2_dof").is_number());
  EXPECT_TRUE(fit.body.contains("history_id"));

  const Reply refused = api.post_json(runs + "/fits", {{"model", {"accel_lever_arm"}}});
  EXPECT_EQ(refused.status, 400) << refused.raw;
  EXPECT_NE(refused.raw.find("body.model"), std::string::npos) << refused.raw;
  EXPECT_NE(refused.raw.find("accel_lever_arm"), std::string::npos) << refused.raw;

  const Reply diagnosis = api.post_json(runs + "/diagnose", nlohmann::json::object());
  ASSERT_EQ(diagnosis.status, 200) << diagnosis.raw;
  EXPECT_EQ(diagnosis.body.at("candidates").size(), 2u);
  EXPECT_TRUE(diagnosis.body.at("candidates")[0].contains("chi2_dof_after"));

  const Reply history = api.get(runs + "/history");
  ASSERT_EQ(history.status, 200);
  ASSERT_EQ(history.body.size(), 2u);  // the fit and the diagnosis; not the refused request
  EXPECT_TRUE(history.body[1].at("rms_turn_deg").is_number());

  const Reply report = api.get(runs + "/report");
  ASSERT_EQ(report.status, 200) << report.raw.substr(0, 300);
  EXPECT_NE(report.raw.find("Recorded without a table"), std::string::npos);
}

}  // namespace

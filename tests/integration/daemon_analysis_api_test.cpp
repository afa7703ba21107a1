// The loop API of calstandd (issue 14) against a daemon in-process on an ephemeral loopback
// port with the simulated station: a fit or diagnosis over the API is exactly `calstand fit
// --json` / `diagnose --json` on the same run, the token is required for POSTs, bad requests
// name the field, and the series downsampling keeps its bounds. The factory line's reads (issue
// 17): the lot, a unit's records and its certificate are `calstand lot`, `calibrations` and
// `certificate` on the same database.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>

#include "cli_runner.hpp"
#include "core/error_terms.hpp"
#include "core/station_config.hpp"
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
  EXPECT_EQ(where(path("/fits"), {{"noise_run", "1"}}, 400), "body.noise_run");
  EXPECT_EQ(where(path("/diagnose"), {{"noise_run", 0}}, 400), "body.noise_run");
  // The run itself as its noise run: its captures at rest are far too short for a noise model.
  EXPECT_EQ(where(path("/fits"), {{"noise_run", run_}}, 400), "noise run " + std::to_string(run_));
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

// The factory line over the API (issue 17): a fixture of two units, one named by its station
// entry and one by the submission (a serial with a space and a slash, as a customer's may be),
// calibrated twice; the second record of the second unit fails its acceptance, so its first
// stays in force. The lot, a unit's records and its certificate are those of `calstand lot`,
// `calibrations` and `certificate`.
class FactoryApi : public ::testing::Test {
 protected:
  static constexpr const char* kFirst = "LOT-A1";
  static constexpr const char* kSecond = "LOT B/2";

  void SetUp() override {
    dir_ = calstand::testing::fresh_dir(
        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    db_ = dir_ + "/station.db";
    core::StationConfig station = sim::load_station_or_default("");
    station.imus[0].serial = kFirst;
    core::ImuConfig second = station.imus[0];
    second.name = "imu1";  // another unit: its errors are drawn with its own seed
    second.serial.clear();
    second.mount_rpy_deg = {0.0, 0.0, 90.0};
    station.imus.push_back(second);
    daemon_ = std::make_unique<InProcessDaemon>(db_, station);
    api_ = std::make_unique<ApiClient>(daemon_->port());
    const Reply submitted = api_->post_json("/runs", {{"procedure", "six-position"},
                                                      {"parameters", {{"capture_s", 5}}},
                                                      {"units", {{"imu1", kSecond}}}});
    ASSERT_EQ(submitted.status, 201) << submitted.raw;
    run_ = submitted.body.at("id");
    ASSERT_TRUE(wait_until([&] {
      const Reply r = api_->get("/runs/" + std::to_string(run_));
      return r.status == 200 && r.body.value("status", "") == "completed";
    }));
    calibrate("accel_bias,gyro_bias,earth_rate");                                 // records 1, 2
    calibrate("accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate");  // 3, 4
    // The first unit's newest record passes; the second unit's fails a chi2/dof no fit meets.
    const std::string runs = "/runs/" + std::to_string(run_);
    Reply r = api_->post(runs + "/acceptance?device=imu0",
                         R"js({"format": "calstand-acceptance/1", "name": "line", "limits": [
                               {"parameter": "accel_bias.*", "max_abs": 0.05, "unit": "m/s^2"}]})js");
    ASSERT_EQ(r.status, 200) << r.raw;
    ASSERT_EQ(r.body.at("verdict"), "pass") << r.raw;
    r = api_->post(runs + "/acceptance?device=imu1",
                   R"js({"format": "calstand-acceptance/1", "name": "strict", "limits": [
                         {"fit": "chi2_dof", "max": 1e-9}]})js");
    ASSERT_EQ(r.status, 200) << r.raw;
    ASSERT_EQ(r.body.at("verdict"), "fail") << r.raw;
  }
  void calibrate(const std::string& model) {
    const auto c =
        calstand::testing::run("calibrate --db " + db_ + " --run " + std::to_string(run_) +
                                   " --model " + model + " --out-dir " + dir_,
                               "/dev/null");
    ASSERT_EQ(c.exit_code, 0) << c.out;
  }
  nlohmann::json cli(const std::string& args) {
    const auto r = calstand::testing::run(args + " --db " + db_ + " --json", "/dev/null");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << r.out;
    return nlohmann::json::parse(r.out, nullptr, false);
  }
  // A path segment percent-encoded (RFC 3986: all but the unreserved characters).
  static std::string encoded(const std::string& segment) {
    std::string out;
    for (const unsigned char c : segment) {
      if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
        out += static_cast<char>(c);
      } else {
        out += fmt::format("%{:02X}", c);
      }
    }
    return out;
  }

  std::string dir_;
  std::string db_;
  std::unique_ptr<InProcessDaemon> daemon_;
  std::unique_ptr<ApiClient> api_;
  std::int64_t run_ = 0;
};

TEST_F(FactoryApi, TheLotIsTheCommandLinesWithBothUnitsAndTheirVerdicts) {
  const Reply lot = api_->get("/lot");
  ASSERT_EQ(lot.status, 200) << lot.raw;
  EXPECT_EQ(lot.body, cli("lot")) << lot.body.dump(1);
  ASSERT_EQ(lot.body.at("units").size(), 2u);
  EXPECT_EQ(lot.body["units"][0]["serial"], kFirst);
  EXPECT_EQ(lot.body["units"][0]["calibration"], 3);  // each unit with its newest record
  EXPECT_EQ(lot.body["units"][0]["verdict"], "pass");
  EXPECT_EQ(lot.body["units"][1]["serial"], kSecond);
  EXPECT_EQ(lot.body["units"][1]["calibration"], 4);
  EXPECT_EQ(lot.body["units"][1]["verdict"], "fail");
  EXPECT_EQ(lot.body["verdicts"]["pass"], 1);
  EXPECT_EQ(lot.body["verdicts"]["fail"], 1);
  EXPECT_DOUBLE_EQ(lot.body["yield"].get<double>(), 0.5);
  // The newest model's parameters (earth_rate, the site's, is no unit's), each with a value per
  // unit and its control limits.
  ASSERT_EQ(lot.body["parameters"].size(), 3u + 3u + 6u + 3u) << lot.body["parameters"];
  for (const auto& p : lot.body["parameters"]) {
    EXPECT_EQ(p["n"], 2) << p.dump();
    EXPECT_EQ(p["values"].size(), 2u) << p.dump();
    EXPECT_LE(p["control"]["lower"].get<double>(), p["mean"].get<double>()) << p.dump();
    EXPECT_GE(p["control"]["upper"].get<double>(), p["mean"].get<double>()) << p.dump();
  }

  const Reply since = api_->get("/lot?since=2000-01-01");
  ASSERT_EQ(since.status, 200) << since.raw;
  EXPECT_EQ(since.body, cli("lot --since 2000-01-01"));
  EXPECT_EQ(since.body["since"], "2000-01-01");
  EXPECT_EQ(since.body["units"].size(), 2u);
  const Reply later = api_->get("/lot?since=9999-12-31T23:59");
  ASSERT_EQ(later.status, 200) << later.raw;
  EXPECT_EQ(later.body["units"].size(), 0u);
  EXPECT_EQ(later.body["parameters"].size(), 0u);

  for (const char* bad : {"yesterday", "2026-13-01", "2026-1-1", "01.12.2026"}) {
    const Reply r = api_->get(std::string("/lot?since=") + bad);
    EXPECT_EQ(r.status, 400) << bad << ": " << r.raw;
    EXPECT_EQ(r.body.value("where", ""), "?since") << r.raw;
    EXPECT_NE(r.body.value("error", "").find(bad), std::string::npos) << r.raw;
  }
  // The command line refuses the same start, naming its option.
  const auto r = calstand::testing::run("lot --since yesterday --db " + db_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("--since"), std::string::npos) << r.out;
}

TEST_F(FactoryApi, AUnitsRecordsAreTheCommandLinesWithTheOneInForce) {
  const Reply second = api_->get("/units/" + encoded(kSecond) + "/calibrations");
  ASSERT_EQ(second.status, 200) << second.raw;
  EXPECT_EQ(second.body, cli(std::string("calibrations --serial '") + kSecond + "'"));
  EXPECT_EQ(second.body["serial"], kSecond);
  const nlohmann::json& records = second.body.at("calibrations");
  ASSERT_EQ(records.size(), 2u) << second.raw;
  // Newest first; the newest failed its acceptance, so the older one is in force.
  EXPECT_EQ(records[0]["id"], 4);
  EXPECT_EQ(records[0]["verdict"], "fail");
  EXPECT_EQ(records[0]["spec"], "strict");
  EXPECT_FALSE(records[0]["in_force"].get<bool>());
  EXPECT_EQ(records[1]["id"], 2);
  EXPECT_TRUE(records[1]["verdict"].is_null());
  EXPECT_TRUE(records[1]["in_force"].get<bool>());
  EXPECT_EQ(records[1]["imu"], "imu1");

  const Reply first = api_->get(std::string("/units/") + kFirst + "/calibrations");
  ASSERT_EQ(first.status, 200) << first.raw;
  ASSERT_EQ(first.body["calibrations"].size(), 2u);
  EXPECT_EQ(first.body["calibrations"][0]["id"], 3);
  EXPECT_TRUE(first.body["calibrations"][0]["in_force"].get<bool>());

  // A serial nobody calibrated has no records, as the command line says.
  const Reply unknown = api_->get("/units/NOBODY/calibrations");
  ASSERT_EQ(unknown.status, 200) << unknown.raw;
  EXPECT_EQ(unknown.body, cli("calibrations --serial NOBODY"));
  EXPECT_EQ(unknown.body["calibrations"].size(), 0u);
}

TEST_F(FactoryApi, ACertificateIsTheUnitsPageAndAnUnknownOneIsNotFound) {
  const Reply page = api_->get("/calibrations/4/certificate");
  if (page.status == 503) {
    EXPECT_EQ(page.body["where"], "gnuplot");
    GTEST_SKIP() << "gnuplot is not installed: the certificate's residual plot needs it";
  }
  ASSERT_EQ(page.status, 200) << page.raw.substr(0, 300);
  EXPECT_EQ(page.raw.rfind("<!DOCTYPE html>", 0), 0u) << page.raw.substr(0, 100);
  bool html = false;
  for (const auto& [k, v] : page.headers) html |= k == "Content-Type" && v.starts_with("text/html");
  EXPECT_TRUE(html);
  // The unit (its serial, HTML-escaped: the slash and the space stay), the record's number and
  // the verdict that keeps it out of force.
  EXPECT_NE(page.raw.find(kSecond), std::string::npos);
  EXPECT_NE(page.raw.find("-000004"), std::string::npos);
  EXPECT_NE(page.raw.find("strict"), std::string::npos);
  // The command line's page of the same record says the same (issued at another moment).
  const auto c = calstand::testing::run(
      "certificate --db " + db_ + " --calibration 4 --out " + dir_ + "/cert.html", "/dev/null");
  ASSERT_EQ(c.exit_code, 0) << c.out;
  const std::string from_cli = calstand::testing::read_text(dir_ + "/cert.html");
  EXPECT_EQ(from_cli.size(), page.raw.size());

  const Reply unknown = api_->get("/calibrations/999/certificate");
  EXPECT_EQ(unknown.status, 404) << unknown.raw;
  EXPECT_EQ(unknown.body.value("where", ""), "/calibrations/999");
  EXPECT_EQ(api_->get("/calibrations/0/certificate").status, 404);
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

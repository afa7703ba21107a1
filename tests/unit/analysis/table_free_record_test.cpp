// `calstand calibrate` on runs without a table: the table-free fit as a calibration record that
// passes its schema, reads back with `calstand apply`'s reader, and holds the session's truth.
#include "analysis/table_free_record.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "../tablefree/session_truth.hpp"
#include "analysis/calibrate.hpp"
#include "analysis/run_model.hpp"
#include "core/error.hpp"
#include "imported_session.hpp"
#include "recorded_run.hpp"
#include "sim/session_folder.hpp"
#include "store/calibrations.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {
namespace {

using testing::import_session;

const nlohmann::json* record_parameter(const nlohmann::json& record, const std::string& name) {
  for (const auto& p : record.at("parameters")) {
    if (p.at("name") == name) return &p;
  }
  return nullptr;
}

TEST(TableFreeRecord, AHandHeldSessionCalibratesIntoARecordHoldingItsTruth) {
  testing::TempDatabase file("tf-record");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 20;
  options.imu.sample_rate_hz = 400.0;
  const sim::SimSession session = sim::simulate_hand_session(options, 13);
  const std::int64_t run = import_session(session, db, "record");

  // The default model (with earth_rate, which such a run leaves out) as `calstand calibrate`.
  const CalibrationOutcome c =
      calibrate_run(db, run, solver::Model::parse(kDefaultModel), "");  // schema-checked inside
  ASSERT_TRUE(c.table_free);
  EXPECT_EQ(c.device, "imu0");
  EXPECT_EQ(c.steps, session.holds.size());
  const nlohmann::json& r = c.record;
  EXPECT_EQ(r.at("method"), "gravity_norm");
  EXPECT_EQ(r.at("frame"), solver::kAccelTriadFrameText);
  EXPECT_EQ(r.at("model").size(), 6u);
  EXPECT_GT(r.at("fit").at("rms_norm_residual_mps2").get<double>(), 0.0);
  EXPECT_GT(r.at("fit").at("rms_turn_residual_deg").get<double>(), 0.0);
  EXPECT_EQ(r.at("fit").at("dof").get<int>(), c.table_free->accel->dof + c.table_free->gyro->dof);
  // The convention's three are given as exactly zero; every estimated one holds the truth.
  const nlohmann::json* xy = record_parameter(r, "accel_misalignment.xy");
  ASSERT_NE(xy, nullptr);
  EXPECT_EQ(xy->at("value").get<double>(), 0.0);
  int checked = 0;
  for (const char* name :
       {"accel_scale.x", "accel_scale.y", "accel_scale.z", "accel_misalignment.zy", "gyro_scale.x",
        "gyro_scale.z", "gyro_misalignment.xy", "gyro_misalignment.zx"}) {
    const nlohmann::json* p = record_parameter(r, name);
    ASSERT_NE(p, nullptr) << name;
    EXPECT_NEAR(p->at("value").get<double>(), solver::testing::session_truth(session, name),
                4.5 * p->at("sigma").get<double>())
        << name;
    ++checked;
  }
  EXPECT_EQ(checked, 8);

  // `calstand apply`'s reader takes it: model and units agree with the catalogue.
  const solver::Calibration read = solver::read_calibration(r, "record.json");
  EXPECT_EQ(read.model.parameters().size(), 24u);
  // The simulated session holds its temperature: the range is that constant.
  EXPECT_NEAR(read.valid_min_c, read.valid_max_c, 1e-9);

  const std::int64_t id = store_calibration(db, c);
  const auto stored = store::calibrations_of_run(db, run);
  ASSERT_EQ(stored.size(), 1u);
  EXPECT_EQ(stored[0].id, id);
  EXPECT_EQ(stored[0].model, table_free_model_text(c.table_free->terms));
  const auto history = store::fit_history(db, run);
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].command, "calibrate");
  EXPECT_EQ(history[0].id, c.history_id);

  // `calstand apply`: the run corrected with its record is still a run without a table, and
  // fitted again it shows no scale factor or misalignment left.
  const ApplyOutcome applied = apply_calibration(db, run, "", read, "record.json");
  EXPECT_EQ(applied.steps, 1u);
  ASSERT_TRUE(needs_table_free_fit(db, applied.run));
  const TableFreeFit again = table_free_fit(db, applied.run, {});
  for (const auto& e : table_free_parameters(again)) {
    if (e.status != solver::EstimateStatus::kEstimated ||
        e.name.find("_bias.") != std::string::npos)
      continue;
    EXPECT_NEAR(e.value, 0.0, 4.5 * e.sigma) << e.name << " left after the correction";
  }
}

TEST(TableFreeRecord, ARecordingWithoutTemperatureHasNoRangeAndStillReadsBack) {
  testing::TempDatabase file("tf-record-notemp");
  store::Database db(file.path());
  const sim::SimSession session = sim::simulate_ferraris_session({}, 6);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("calstand-tf-notemp-" + std::to_string(::getpid()));
  sim::SessionFolderOptions options;
  options.temperature = false;
  sim::write_session_folder(session, dir, options);
  const std::int64_t run = store::import_run(db, dir).run;
  std::filesystem::remove_all(dir);

  const CalibrationOutcome c = calibrate_run(db, run, solver::Model::parse(kDefaultModel), "");
  EXPECT_EQ(c.record.at("method"), "ferraris");
  EXPECT_TRUE(c.record.at("temperature_ref_c").is_null());
  EXPECT_TRUE(c.record.at("valid_temperature_c").at("min").is_null());
  EXPECT_FALSE(c.record.at("fit").contains("rms_turn_residual_deg"));
  const solver::Calibration read = solver::read_calibration(c.record, "record.json");
  EXPECT_TRUE(std::isinf(read.valid_min_c) && read.valid_min_c < 0);
  EXPECT_TRUE(std::isinf(read.valid_max_c) && read.valid_max_c > 0);
  // Asking a Ferraris session for g-sensitivity is refused before anything is stored.
  EXPECT_THROW(calibrate_run(db, run, solver::Model::parse("gyro_bias,gyro_g_sensitivity"), ""),
               core::InputError);
  EXPECT_EQ(store::fit_history(db, run).size(), 1u);
}

}  // namespace
}  // namespace calstand::analysis

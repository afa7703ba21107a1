// What a certificate draws from the fit that made its record: the step residuals stored with
// the record (no refit), equal to the calibration's own; a record stored without them (made
// before schema version 7) gets the same residuals by a refit, and the same page.
#include <gtest/gtest.h>

#include <cmath>

#include "../analysis/recorded_run.hpp"
#include "analysis/calibrate.hpp"
#include "core/error.hpp"
#include "factory/certificate.hpp"
#include "render/gnuplot_svg.hpp"
#include "store/calibrations.hpp"
#include "store/sample_reader.hpp"

namespace calstand::analysis {
namespace {

constexpr const char* kCertificateModel =
    "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";

class CertificateResiduals : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = testing::record_run(file_.path(), "six-position", {"capture_s=10"}, 4);
    store::Database db(file_.path());
    calibration_ = calibrate_run(db, run_, solver::Model::parse(kCertificateModel), "");
    id_ = store_calibration(db, calibration_);
  }
  testing::TempDatabase file_{"certificate"};
  std::int64_t run_ = 0;
  CalibrationOutcome calibration_;
  std::int64_t id_ = 0;
};

void expect_same_steps(const std::vector<solver::StepResidual>& a,
                       const std::vector<solver::StepResidual>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].index, b[k].index) << k;
    EXPECT_EQ(a[k].label, b[k].label) << k;
    for (Eigen::Index c = 0; c < 6; ++c) {
      // The stored numbers round-trip JSON exactly (17 significant digits).
      EXPECT_EQ(a[k].residual(c), b[k].residual(c)) << k << " " << c;
      EXPECT_EQ(a[k].sigma(c), b[k].sigma(c)) << k << " " << c;
    }
  }
}

TEST_F(CertificateResiduals, ReadsTheStoredStepResidualsWithoutReadingTheRunAgain) {
  store::Database db(file_.path());
  ASSERT_TRUE(store::load_calibration_residuals(db, id_).has_value());
  const std::uint64_t decoded = store::samples_decoded();
  const CertificateData d = certificate_data(db, id_);
  EXPECT_EQ(store::samples_decoded(), decoded) << "the certificate refitted the model";
  EXPECT_FALSE(d.residuals_refitted);
  ASSERT_TRUE(d.residuals.has_value());
  EXPECT_EQ(d.residuals->size(), 6u);
  expect_same_steps(*d.residuals, calibration_.fit.steps);
}

TEST_F(CertificateResiduals, ARecordWithoutStoredResidualsIsRefittedAndLooksTheSame) {
  store::Database db(file_.path());
  const CertificateData stored = certificate_data(db, id_);
  // A record as a calibration made before schema version 7 left it: no residuals beside it.
  db.sql().exec("DELETE FROM calibration_residuals WHERE calibration_id = " + std::to_string(id_));
  ASSERT_FALSE(store::load_calibration_residuals(db, id_).has_value());
  const std::uint64_t decoded = store::samples_decoded();
  CertificateData old = certificate_data(db, id_);
  EXPECT_GT(store::samples_decoded(), decoded) << "a refit reads the run";
  EXPECT_TRUE(old.residuals_refitted);
  ASSERT_TRUE(old.residuals.has_value());
  expect_same_steps(*old.residuals, *stored.residuals);
  try {
    find_gnuplot();
  } catch (const core::InputError&) {
    GTEST_SKIP() << "gnuplot is not installed: the page is not drawn";
  }
  old.issued_utc = stored.issued_utc;  // the one thing that differs: when it was issued
  EXPECT_EQ(certificate_html(old), certificate_html(stored));
}

TEST_F(CertificateResiduals, AMalformedStoredDocumentIsRefusedByName) {
  store::Database db(file_.path());
  db.sql().exec(
      "UPDATE calibration_residuals SET steps = '{\"format\": \"x\"}' WHERE "
      "calibration_id = " +
      std::to_string(id_));
  try {
    certificate_data(db, id_);
    FAIL() << "a document of another format was read";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("calstand-step-residuals/1"), std::string::npos)
        << e.what();
    EXPECT_NE(e.where().find("calibration " + std::to_string(id_)), std::string::npos) << e.where();
  }
}

}  // namespace
}  // namespace calstand::analysis

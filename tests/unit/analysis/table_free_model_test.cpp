// Which terms a run without a table can be fitted with: the model as --model or a request
// gives it, read against what such a run knows.
#include "analysis/table_free_model.hpp"

#include <gtest/gtest.h>

#include "analysis/run_model.hpp"
#include "core/error.hpp"

namespace calstand::analysis {
namespace {

TEST(TableFreeModel, TheDefaultModelFitsTheBaseTermsAndLeavesTheEarthRateOutWithANote) {
  const TableFreeModel m = table_free_model(solver::Model::parse(kDefaultModel));
  EXPECT_EQ(m.terms, TableFreeTerms{});
  ASSERT_EQ(m.notes.size(), 1u);
  EXPECT_NE(m.notes[0].find("earth_rate"), std::string::npos);
  EXPECT_NE(m.notes[0].find("heading"), std::string::npos);
  EXPECT_EQ(table_free_model_text(m.terms),
            "gyro_bias,gyro_scale,gyro_misalignment,accel_bias,accel_scale,accel_misalignment");
}

TEST(TableFreeModel, OptionalTermsAreTakenAndReadBackInTheirOrder) {
  const TableFreeModel m =
      table_free_model(solver::Model::parse("accel_quadratic,gyro_bias,gyro_g_sensitivity"));
  EXPECT_TRUE(m.terms.gyro_g_sensitivity);
  EXPECT_TRUE(m.terms.accel_quadratic);
  EXPECT_TRUE(m.notes.empty());
  const std::string text = table_free_model_text(m.terms);
  EXPECT_EQ(text.substr(text.size() - 35), ",gyro_g_sensitivity,accel_quadratic");
  // The text is a model the catalogue reads, and it reads back to the same terms.
  EXPECT_EQ(table_free_model(solver::Model::parse(text)).terms, m.terms);
  EXPECT_EQ(with_table_free_term({}, "accel_quadratic").accel_quadratic, true);
  EXPECT_THROW(with_table_free_term({}, "earth_rate"), core::InputError);
}

TEST(TableFreeModel, TermsThatNeedATableOrAChamberAreRefusedByNameAndWhy) {
  for (const auto& [term, why] : std::vector<std::pair<std::string, std::string>>{
           {"gyro_temp_bias:2", "temperature steps"},
           {"accel_lever_arm", "describes the table"},
           {"table_tilt", "describes the table"},
           {"gyro_scale_asymmetry", "do not model it"}}) {
    try {
      table_free_model(solver::Model::parse("gyro_bias," + term));
      FAIL() << term << " was taken";
    } catch (const core::InputError& e) {
      EXPECT_EQ(e.where(), "model");
      const std::string what = e.what();
      EXPECT_NE(what.find(term.substr(0, term.find(':'))), std::string::npos) << what;
      EXPECT_NE(what.find(why), std::string::npos) << what;
      EXPECT_NE(what.find("gyro_g_sensitivity"), std::string::npos) << "offers the others";
    }
  }
  EXPECT_THROW(table_free_model(solver::Model::parse("k", {"k=gyro:rate_x^2"})), core::InputError);
}

}  // namespace
}  // namespace calstand::analysis

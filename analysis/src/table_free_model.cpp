// Which error terms a run without a table can be fitted with.
#include "analysis/table_free_model.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "core/error.hpp"

namespace calstand::analysis {
namespace {

// What a term the table-free methods cannot fit needs, in the words of an error message.
std::string why_not_without_table(const std::string& term) {
  if (term.find("_temp_") != std::string::npos) {
    return "a thermal term needs temperature steps with a known orientation (a chamber run on "
           "the table)";
  }
  if (term == "accel_lever_arm" || term == "table_tilt") {
    return "it describes the table, and this run has none";
  }
  return "the table-free methods (gravity norm, integration between poses, Ferraris) do not "
         "model it";
}

}  // namespace

const std::vector<std::string>& table_free_base_terms() {
  static const std::vector<std::string> terms = {"gyro_bias",  "gyro_scale",  "gyro_misalignment",
                                                 "accel_bias", "accel_scale", "accel_misalignment"};
  return terms;
}

const std::vector<std::string>& table_free_optional_terms() {
  static const std::vector<std::string> terms = {"gyro_g_sensitivity", "accel_quadratic"};
  return terms;
}

TableFreeTerms with_table_free_term(TableFreeTerms terms, const std::string& name, bool on) {
  if (name == "gyro_g_sensitivity") {
    terms.gyro_g_sensitivity = on;
  } else if (name == "accel_quadratic") {
    terms.accel_quadratic = on;
  } else {
    throw core::InputError("model",
                           fmt::format("{} is no optional term of a table-free fit", name));
  }
  return terms;
}

bool has_table_free_term(const TableFreeTerms& terms, const std::string& name) {
  if (name == "gyro_g_sensitivity") return terms.gyro_g_sensitivity;
  if (name == "accel_quadratic") return terms.accel_quadratic;
  return false;
}

TableFreeModel table_free_model(const solver::Model& model) {
  if (!model.customs().empty()) {
    throw core::InputError(
        "model", fmt::format("custom term {}: custom terms are fitted to table step means; a "
                             "run without a table has none",
                             model.customs().front().name));
  }
  TableFreeModel out;
  const auto& base = table_free_base_terms();
  const auto& optional = table_free_optional_terms();
  for (const solver::ModelTerm& t : model.terms()) {
    const std::string name(t.info->name);
    if (std::find(base.begin(), base.end(), name) != base.end()) continue;
    if (std::find(optional.begin(), optional.end(), name) != optional.end()) {
      out.terms = with_table_free_term(out.terms, name);
      continue;
    }
    if (name == "earth_rate") {
      out.notes.push_back(
          "earth_rate is no fitted term here: the integration between poses models the Earth "
          "rate whenever the run has a site latitude (W sin(latitude) along gravity; across "
          "it W cos(latitude) towards North, whose heading at the initial rest is fitted as a "
          "nuisance parameter), and takes it out of the gyro bias of the initial rest");
      continue;
    }
    throw core::InputError(
        "model", fmt::format("{} cannot be fitted on a run without a table: {} (terms offered "
                             "here: the bias, scale factor and misalignment of both triads, {})",
                             name, why_not_without_table(name), fmt::join(optional, ", ")));
  }
  return out;
}

std::vector<std::string> table_free_model_terms(const TableFreeTerms& terms) {
  std::vector<std::string> out = table_free_base_terms();
  for (const auto& name : table_free_optional_terms()) {
    if (has_table_free_term(terms, name)) out.push_back(name);
  }
  return out;
}

std::string table_free_model_text(const TableFreeTerms& terms) {
  return fmt::format("{}", fmt::join(table_free_model_terms(terms), ","));
}

}  // namespace calstand::analysis

#pragma once
// Which error terms a run without a table can be fitted with. Such a run knows no orientation:
// its calibration (table_free_fit.hpp) always fits the bias, scale factor and misalignment of
// both triads, and can add the few terms its methods support; the others need what the run
// lacks (a table for the lever arm and tilt, temperature steps for thermal terms). The Earth
// rate is no term of such a fit: the integration between poses models it from the site
// latitude whatever the model says (table_free_fit.hpp). A model given as `--model` or in a request
// is read against that list.

#include <string>
#include <vector>

#include "solver/model.hpp"

namespace calstand::analysis {

/// The terms of a table-free fit beyond those every such fit has.
struct TableFreeTerms {
  bool gyro_g_sensitivity = false;  ///< gyro_g_sensitivity (gyro integration between poses)
  bool accel_quadratic = false;     ///< accel_quadratic (gravity norm)

  bool operator==(const TableFreeTerms&) const = default;
};

/// The terms every table-free fit has, in the catalogue's order.
const std::vector<std::string>& table_free_base_terms();

/// The terms a table-free fit may add, in the order a diagnosis tries them.
const std::vector<std::string>& table_free_optional_terms();

/// `terms` with the optional term `name` set or cleared; core::InputError for another name.
TableFreeTerms with_table_free_term(TableFreeTerms terms, const std::string& name, bool on = true);

/// True when `terms` has the optional term `name`.
bool has_table_free_term(const TableFreeTerms& terms, const std::string& name);

/// A model read for a run without a table.
struct TableFreeModel {
  TableFreeTerms terms;
  /// What was left out of the model as given, and why (earth_rate: modelled from the latitude
  /// with the heading fitted, not a term).
  std::vector<std::string> notes;
};

/// Reads `model` for a run without a table: the base terms are fitted whether listed or not,
/// `earth_rate` (in the default model) is no term here (a note says how the Earth rate is
/// handled), the optional terms are taken.
/// Throws core::InputError (where "model") naming any other term and what it needs that the
/// run lacks, and for custom terms (their signals are table signals).
TableFreeModel table_free_model(const solver::Model& model);

/// The terms of a table-free fit with `terms`: base terms, then the optional ones fitted.
std::vector<std::string> table_free_model_terms(const TableFreeTerms& terms);

/// The comma-separated terms of a table-free fit with `terms` (base terms, then the optional
/// ones fitted), as `--model` reads them back.
std::string table_free_model_text(const TableFreeTerms& terms);

}  // namespace calstand::analysis

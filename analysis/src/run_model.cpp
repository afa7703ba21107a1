#include "analysis/run_model.hpp"

#include <fmt/format.h>

#include "solver/custom_term.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

// The reason of an InputError without its place: e.what() is "where: why".
std::string reason_of(const core::InputError& e) {
  const std::string what = e.what();
  const std::string prefix = e.where().empty() ? "" : e.where() + ": ";
  return what.starts_with(prefix) ? what.substr(prefix.size()) : what;
}

}  // namespace

solver::SensorRows parse_sensor_rows(const std::string& sensor, const std::string& where) {
  if (sensor == "gyro") return solver::SensorRows::kGyro;
  if (sensor == "accel") return solver::SensorRows::kAccel;
  if (sensor == "both") return solver::SensorRows::kBoth;
  throw core::InputError(where, "must be both, gyro or accel");
}

solver::Model model_from_lists(const std::vector<std::string>& terms,
                               const std::vector<std::string>& customs) {
  // Each entry is checked alone first so that the error names the entry, not the whole list
  // (the solver's parser names the command line's --model and --custom).
  for (std::size_t i = 0; i < customs.size(); ++i) {
    try {
      solver::parse_custom_term(customs[i], "custom");
    } catch (const core::InputError& e) {
      throw core::InputError(fmt::format("custom[{}]", i), reason_of(e));
    }
  }
  std::string joined;
  for (std::size_t i = 0; i < terms.size(); ++i) {
    if (terms[i].find(',') != std::string::npos) {
      throw core::InputError(fmt::format("model[{}]", i), "one term per entry (no commas)");
    }
    try {
      solver::Model::parse(terms[i], customs);
    } catch (const core::InputError& e) {
      throw core::InputError(fmt::format("model[{}]", i), reason_of(e));
    }
    joined += (joined.empty() ? "" : ",") + terms[i];
  }
  try {
    return solver::Model::parse(terms.empty() ? std::string(kDefaultModel) : joined, customs);
  } catch (const core::InputError& e) {
    // Only what involves several entries is left: a term or a custom name given twice.
    const bool custom = e.where().starts_with("--custom");
    throw core::InputError(custom ? "custom" : "model", reason_of(e));
  }
}

void require_fit_run(store::Database& db, std::int64_t run) {
  store::RunStore runs(db);
  try {
    runs.run_status(run);  // throws for an unknown run
  } catch (const core::InputError& e) {
    throw RunNotFound(e.where(), reason_of(e));
  }
  if (store::sample_devices(db, run).empty()) {
    throw NothingToFit(fmt::format("run {}", run), "has no samples");
  }
}

std::string choose_fit_device(store::Database& db, std::int64_t run, const std::string& device) {
  require_fit_run(db, run);
  return store::choose_device(db, run, device);
}

solver::RunData load_fit_data(store::Database& db, std::int64_t run, const std::string& device) {
  const std::string chosen = choose_fit_device(db, run, device);
  store::RunStore runs(db);
  solver::RunData data;
  data.setup = solver::run_setup(runs.load_run(run), run, chosen);
  data.steps = store::read_step_data(db, run, chosen);
  if (data.steps.empty()) {
    throw NothingToFit(fmt::format("run {}", run), "has no completed steps with samples");
  }
  return data;
}

}  // namespace calstand::analysis

#include "solver/calibration_record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "store/stamp.hpp"

namespace calstand::solver {
namespace {

constexpr int kCorrectionIterations = 6;

}  // namespace

nlohmann::json make_calibration_record(const RunSetup& setup, const Model& model,
                                       const FitResult& fit, const std::vector<StepSummary>& steps,
                                       const nlohmann::json& noise) {
  double tmin = std::numeric_limits<double>::infinity();
  double tmax = -tmin;
  for (const auto& s : steps) {
    tmin = std::min(tmin, s.signals[0]);
    tmax = std::max(tmax, s.signals[0]);
  }
  nlohmann::ordered_json r;
  r["format"] = kCalibrationFormat;
  r["device"] = {{"name", setup.device}, {"model", setup.imu_model}, {"serial", setup.imu_serial}};
  r["station"] = setup.station;
  r["runs"] = {setup.run};
  r["procedure"] = {{"name", setup.procedure_name}, {"sha256", setup.procedure_sha256}};
  r["model"] = fit.terms;
  r["custom_terms"] = nlohmann::json::array();
  for (const auto& c : model.customs()) r["custom_terms"].push_back(c.text());
  r["parameters"] = nlohmann::json::array();
  for (const auto& p : fit.parameters) {
    r["parameters"].push_back(
        {{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}, {"unit", p.unit}});
  }
  r["unidentifiable"] = nlohmann::json::array();
  for (const auto& u : fit.unidentifiable) {
    r["unidentifiable"].push_back({{"name", u.name}, {"reason", u.reason}});
  }
  const nlohmann::json fit_json = fit_to_json(fit);
  r["fit"] = {{"chi2_dof", fit.chi2_dof},
              {"dof", fit.dof},
              {"residual_rms", fit_json["residual_rms"]},
              {"noise_floor", fit_json["noise_floor"]},
              {"noise_model", fit_json["noise_model"]}};
  if (!noise.is_null()) r["noise"] = noise;
  r["temperature_ref_c"] = setup.temperature_ref_c;
  r["valid_temperature_c"] = {{"min", tmin}, {"max", tmax}};
  r["created_utc"] = store::utc_now_iso8601();
  r["software"] = kSoftwareVersion;
  return nlohmann::json::parse(r.dump());
}

Calibration read_calibration(const nlohmann::json& record, const std::string& file_name) {
  core::validate_or_throw(core::schema("calibration.schema.json"), record, file_name);
  Calibration c;
  c.record = record;
  std::string terms;
  for (const auto& t : record["model"]) terms += (terms.empty() ? "" : ",") + t.get<std::string>();
  std::vector<std::string> customs;
  for (const auto& t : record.value("custom_terms", nlohmann::json::array())) {
    customs.push_back(t.get<std::string>());
  }
  try {
    c.model = Model::parse(terms, customs);
  } catch (const core::InputError& e) {
    throw core::InputError(file_name + ": model", e.what());
  }
  c.values = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(c.model.size()));
  const auto& params = record["parameters"];
  for (std::size_t i = 0; i < params.size(); ++i) {
    const std::string name = params[i]["name"].get<std::string>();
    const auto& list = c.model.parameters();
    const auto it = std::find_if(list.begin(), list.end(),
                                 [&](const ParameterInfo& p) { return p.name == name; });
    if (it == list.end()) {
      throw core::InputError(fmt::format("{}: parameters[{}].name", file_name, i),
                             fmt::format("\"{}\" is not a parameter of the record's model", name));
    }
    if (it->unit != params[i]["unit"].get<std::string>()) {
      throw core::InputError(fmt::format("{}: parameters[{}].unit", file_name, i),
                             fmt::format("\"{}\" must be in {}", name, it->unit));
    }
    c.values[it - list.begin()] = params[i]["value"].get<double>();
  }
  // A record of a recording without temperature has no thermal term and no range: T_ref is
  // then unused, and every temperature is inside the (unbounded) range.
  const auto number_or = [](const nlohmann::json& v, double fallback) {
    return v.is_number() ? v.get<double>() : fallback;
  };
  c.temperature_ref_c = number_or(record["temperature_ref_c"], c.temperature_ref_c);
  c.valid_min_c =
      number_or(record["valid_temperature_c"]["min"], -std::numeric_limits<double>::infinity());
  c.valid_max_c =
      number_or(record["valid_temperature_c"]["max"], std::numeric_limits<double>::infinity());
  return c;
}

namespace {

RunSetup with_reference_temperature(RunSetup setup, double temperature_ref_c) {
  setup.temperature_ref_c = temperature_ref_c;  // the record's dT, not the run's
  return setup;
}

}  // namespace

Corrector::Corrector(const Calibration& calibration, const RunSetup& setup)
    : model_(calibration.model),
      values_(calibration.values),
      build_(with_reference_temperature(setup, calibration.temperature_ref_c), false) {
  // The table tilt belongs to the station, not the IMU: it is not removed from the samples.
  for (std::size_t p = 0; p < model_.size(); ++p) {
    if (model_.parameters()[p].name.rfind("table_tilt.", 0) == 0)
      values_[static_cast<Eigen::Index>(p)] = 0.0;
  }
}

void Corrector::correct(store::StepData& step, double run_start_s) const {
  const std::vector<double> temperature_rates = step_temperature_rates(step.samples);
  Eigen::MatrixXd g(kChannels, static_cast<Eigen::Index>(model_.size()));
  for (std::size_t i = 0; i < step.samples.size(); ++i) {
    core::ImuSample& s = step.samples[i];
    const Eigen::Vector3d measured_w = s.gyro_dps;
    const Eigen::Vector3d measured_f = s.accel_mps2;
    Eigen::Vector3d w = measured_w;
    Eigen::Vector3d f = measured_f;
    for (int it = 0; it < kCorrectionIterations && model_.size() > 0; ++it) {
      const Signals sig = build_.with_inputs(w, f, step.table[i], s.temperature_c,
                                             temperature_rates[i], s.receive_time_s - run_start_s);
      model_.regressors(sig, g);
      const Vector6d error = g * values_;
      w = measured_w - error.head<3>();
      f = measured_f - error.tail<3>();
    }
    s.gyro_dps = w;
    s.accel_mps2 = f;
  }
}

}  // namespace calstand::solver

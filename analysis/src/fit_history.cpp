#include "analysis/fit_history.hpp"

namespace calstand::analysis {
namespace {

nlohmann::json or_null(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json();
}

}  // namespace

store::FitRecord history_record(std::int64_t run, const std::string& device,
                                const std::string& command, const solver::Model& model,
                                const solver::FitResult& fit, const std::string& sensors) {
  store::FitRecord r;
  r.run = run;
  r.device = device;
  r.command = command;
  r.model = fit.model;
  for (const auto& c : model.customs()) r.custom_terms.push_back(c.text());
  r.sensors = sensors;
  r.parameters = static_cast<int>(fit.parameters.size());
  r.chi2_dof = fit.chi2_dof;
  if (fit.rows != solver::SensorRows::kAccel) r.rms_gyro_dps = fit.residual_rms_gyro_dps;
  if (fit.rows != solver::SensorRows::kGyro) r.rms_accel_mps2 = fit.residual_rms_accel_mps2;
  return r;
}

std::int64_t record_history(store::Database& db, std::int64_t run, const std::string& device,
                            const std::string& command, const solver::Model& model,
                            const solver::FitResult& fit, const std::string& sensors) {
  return store::record_fit(db, history_record(run, device, command, model, fit, sensors));
}

nlohmann::json history_to_json(const std::vector<store::FitRecord>& fits) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& f : fits) {
    out.push_back({{"id", f.id},
                   {"command", f.command},
                   {"model", f.model},
                   {"custom_terms", f.custom_terms},
                   {"sensors", f.sensors},
                   {"parameters", f.parameters},
                   {"chi2_dof", or_null(f.chi2_dof)},
                   {"rms_gyro_dps", or_null(f.rms_gyro_dps)},
                   {"rms_accel_mps2", or_null(f.rms_accel_mps2)},
                   {"rms_turn_deg", or_null(f.rms_turn_deg)},
                   {"time", f.created_utc}});
  }
  return out;
}

}  // namespace calstand::analysis

// The calibration of a run without a table: Ferraris for labelled sections, else the static
// detector, the gravity norm and the integration between poses.
#include "analysis/table_free_fit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "analysis/run_model.hpp"
#include "core/site.hpp"
#include "store/fit_history.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

// Local g of a table-free run: the import's site.gravity_mps2 (required there without a table).
double run_gravity(store::Database& db, std::int64_t run) {
  store::RunStore runs(db);
  const nlohmann::json snapshot = runs.load_run(run).station_snapshot;
  const auto site = snapshot.find("site");
  if (site == snapshot.end() || !site->contains("gravity_mps2") ||
      !(*site)["gravity_mps2"].is_number()) {
    throw core::InputError(fmt::format("run {}", run),
                           "has no site.gravity_mps2: a run without a table is calibrated by "
                           "the gravity norm, which needs local g");
  }
  return (*site)["gravity_mps2"].get<double>();
}

// The site's latitude [deg] of a run (the import's site.latitude_deg, the station's site):
// the integration between poses models the Earth rate with it. Empty when the run does not
// carry one.
std::optional<double> run_latitude(store::Database& db, std::int64_t run) {
  store::RunStore runs(db);
  const nlohmann::json snapshot = runs.load_run(run).station_snapshot;
  const auto site = snapshot.find("site");
  if (site == snapshot.end() || !site->is_object() || !site->contains("latitude_deg") ||
      !(*site)["latitude_deg"].is_number()) {
    return std::nullopt;
  }
  return (*site)["latitude_deg"].get<double>();
}

// Every sample of the run's completed steps, in time order, with the step each came from.
struct RunSamples {
  std::vector<core::ImuSample> samples;
  std::vector<const store::StepData*> step_of;  ///< per sample
  std::vector<store::StepData> steps;
};

RunSamples read_samples(store::Database& db, std::int64_t run, const std::string& device) {
  RunSamples r;
  r.steps = store::read_step_data(db, run, device);
  if (r.steps.empty()) {
    throw NothingToFit(fmt::format("run {}", run), "has no completed steps with samples");
  }
  std::vector<std::pair<const core::ImuSample*, const store::StepData*>> all;
  for (const auto& s : r.steps)
    for (const auto& sample : s.samples) all.emplace_back(&sample, &s);
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.first->receive_time_s < b.first->receive_time_s;
  });
  r.samples.reserve(all.size());
  r.step_of.reserve(all.size());
  for (const auto& [sample, step] : all) {
    r.samples.push_back(*sample);
    r.step_of.push_back(step);
  }
  return r;
}

// The operator's intervals as the detector would give them: sample ranges with their means.
solver::StaticDetection given_intervals(const std::vector<core::ImuSample>& samples,
                                        const std::vector<std::pair<double, double>>& spans) {
  solver::StaticDetection d;
  d.rule_text = "intervals given by the operator";
  for (std::size_t k = 0; k < spans.size(); ++k) {
    const auto [from_s, to_s] = spans[k];
    const std::string where = fmt::format("--static-intervals[{}]", k);
    if (!(std::isfinite(from_s) && std::isfinite(to_s) && from_s < to_s)) {
      throw core::InputError(where, fmt::format("{:g} to {:g} s is not an interval", from_s, to_s));
    }
    if (k > 0 && from_s < spans[k - 1].second) {
      throw core::InputError(where, "overlaps or precedes the interval before it");
    }
    const auto first =
        std::lower_bound(samples.begin(), samples.end(), from_s,
                         [](const core::ImuSample& s, double t) { return s.receive_time_s < t; });
    const auto last =
        std::upper_bound(samples.begin(), samples.end(), to_s,
                         [](double t, const core::ImuSample& s) { return t < s.receive_time_s; });
    if (last - first < 2) {
      throw core::InputError(where, fmt::format("{:g} to {:g} s holds fewer than 2 samples of "
                                                "the recording ({:g} to {:g} s)",
                                                from_s, to_s, samples.front().receive_time_s,
                                                samples.back().receive_time_s));
    }
    solver::StaticInterval iv;
    iv.begin = static_cast<std::size_t>(first - samples.begin());
    iv.end = static_cast<std::size_t>(last - samples.begin());
    iv.start_s = first->receive_time_s;
    iv.end_s = (last - 1)->receive_time_s;
    iv.initial_rest = k == 0;
    for (auto it = first; it != last; ++it) {
      iv.mean_accel_mps2 += it->accel_mps2;
      iv.mean_gyro_dps += it->gyro_dps;
    }
    iv.mean_accel_mps2 /= static_cast<double>(last - first);
    iv.mean_gyro_dps /= static_cast<double>(last - first);
    d.intervals.push_back(iv);
  }
  d.has_initial_rest = !d.intervals.empty();
  if (d.has_initial_rest) {
    d.rest_start_s = d.intervals.front().start_s;
    d.rest_end_s = d.intervals.front().end_s;
  }
  return d;
}

// The import's section of a step, as the Ferraris method names it ("x_p", "y_rot"...), with
// the turn's nominal size [deg] (its sign comes from the data); nullopt for a step that is no
// labelled hold or turn.
std::optional<solver::FerrarisSection> ferraris_section(const store::StepRecord& step) {
  const auto it = step.commanded.find("section");
  if (it == step.commanded.end() || !it->is_object()) return std::nullopt;
  const nlohmann::json& s = *it;
  const std::string kind = s.value("kind", "");
  solver::FerrarisSection section;
  if (kind == "static" && s.contains("up")) {
    const std::string up = s["up"].get<std::string>();
    section.label = fmt::format("{}_{}", up.substr(1), up[0] == '+' ? "p" : "a");
  } else if (kind == "turn" && s.contains("axis")) {
    const std::string axis = s["axis"].get<std::string>();
    section.label = axis.substr(1) + "_rot";
    section.angle_deg = std::abs(s.value("angle_deg", 360.0));
  } else {
    return std::nullopt;
  }
  return section;
}

// Ferraris sections when steps of the run are labelled holds or turns (the moves between them
// may be steps of their own, unlabelled); nullopt when none is.
std::optional<std::vector<solver::FerrarisSection>> labelled_sections(const RunSamples& r) {
  std::vector<solver::FerrarisSection> sections;
  for (const auto& step : r.steps) {
    auto section = ferraris_section(step.step);
    if (!section) continue;
    // The step's samples are contiguous in time order (sections do not interleave).
    const auto first = std::find(r.step_of.begin(), r.step_of.end(), &step);
    const auto last = std::find(r.step_of.rbegin(), r.step_of.rend(), &step);
    section->begin = static_cast<std::size_t>(first - r.step_of.begin());
    section->end = static_cast<std::size_t>(r.step_of.rend() - last);
    sections.push_back(*section);
  }
  if (sections.empty()) return std::nullopt;
  return sections;
}

// The device of a table-free run, after the checks of any fit; a run with a table is refused.
std::string table_free_device(store::Database& db, std::int64_t run, const std::string& device) {
  std::string chosen = choose_fit_device(db, run, device);
  if (store::orientation_known(db, run)) {
    throw core::InputError(fmt::format("run {}", run),
                           "has a known orientation (a table); its steps are fitted by the "
                           "classical model, not by static-pose detection");
  }
  return chosen;
}

// The poses in samples already read: the operator's intervals, or the detector's.
TableFreePoses poses_of(std::int64_t run, std::string device, RunSamples&& r,
                        const TableFreeFitRequest& request) {
  TableFreePoses poses;
  poses.run = run;
  poses.device = std::move(device);
  poses.samples = std::move(r.samples);
  poses.given = !request.intervals_s.empty();
  poses.detection = poses.given ? given_intervals(poses.samples, request.intervals_s)
                                : solver::detect_static_intervals(poses.samples, request.detector);
  return poses;
}

// The gravity norm and the integration between `fit.poses` with `fit.terms`; `referrals`:
// the poses referred as another fit referred them (a candidate judged on its base's data).
void calibrate_poses(TableFreeFit& fit,
                     const std::vector<solver::GyroHoldReferral>& referrals = {}) {
  solver::GravityNormOptions accel_options;
  accel_options.gravity_mps2 = fit.gravity_mps2;
  accel_options.fit_quadratic = fit.terms.accel_quadratic;
  fit.accel = solver::calibrate_accel_gravity_norm(fit.poses->samples,
                                                   fit.poses->detection.intervals, accel_options);
  solver::GyroIntegrationOptions gyro_options;
  gyro_options.fit_g_sensitivity = fit.terms.gyro_g_sensitivity;
  if (fit.earth_rate) gyro_options.latitude_deg = fit.latitude_deg;
  gyro_options.referrals = referrals;
  fit.gyro = solver::calibrate_gyro_integration(fit.poses->samples, fit.poses->detection.intervals,
                                                *fit.accel, gyro_options);
}

}  // namespace

TableFreeFitRequest table_free_request(const solver::Model& model, TableFreeFitRequest poses) {
  TableFreeModel read = table_free_model(model);
  poses.terms = read.terms;
  poses.notes = std::move(read.notes);
  return poses;
}

TableFreeFit refit_table_free(const TableFreeFit& fit, const TableFreeTerms& terms) {
  if (!fit.poses) {
    throw core::InputError("model", fmt::format("run {} is a labelled Ferraris session: it takes "
                                                "no optional term",
                                                fit.run));
  }
  TableFreeFit out = fit;
  out.terms = terms;
  out.history_id.reset();
  // The same poses referred the same way: a candidate is judged on the data and weights of
  // the model it extends (the referral's known still rate moves with the terms fitted).
  calibrate_poses(out, fit.gyro ? fit.gyro->referrals : std::vector<solver::GyroHoldReferral>{});
  return out;
}

bool needs_table_free_fit(store::Database& db, std::int64_t run) {
  require_fit_run(db, run);  // RunNotFound for an unknown run (any number of IMUs)
  return !store::orientation_known(db, run);
}

TableFreePoses table_free_poses(store::Database& db, std::int64_t run,
                                const TableFreeFitRequest& request) {
  std::string device = table_free_device(db, run, request.device);
  RunSamples r = read_samples(db, run, device);
  return poses_of(run, std::move(device), std::move(r), request);
}

TableFreeFit table_free_fit(store::Database& db, std::int64_t run,
                            const TableFreeFitRequest& request) {
  TableFreeFit fit;
  fit.run = run;
  fit.device = table_free_device(db, run, request.device);
  fit.gravity_mps2 = run_gravity(db, run);
  fit.terms = request.terms;
  fit.notes = request.notes;
  fit.earth_rate = request.earth_rate;
  fit.latitude_deg = run_latitude(db, run);
  if (fit.earth_rate && !fit.latitude_deg) {
    fit.notes.push_back(
        "earth_rate not modelled: the run has no site latitude, so not even its vertical part "
        "(W sin(latitude) along gravity) is known; the gyro integration leaves it out (on a "
        "tactical-grade gyro it then looks like an isotropic g-sensitivity of about 0.003 "
        "(deg/s)/g)");
  }
  RunSamples r = read_samples(db, run, fit.device);  // once, for whichever method
  for (const core::ImuSample& sample : r.samples) {
    if (!std::isfinite(sample.temperature_c)) continue;
    fit.min_temperature_c = std::isnan(fit.min_temperature_c)
                                ? sample.temperature_c
                                : std::min(fit.min_temperature_c, sample.temperature_c);
    fit.max_temperature_c = std::isnan(fit.max_temperature_c)
                                ? sample.temperature_c
                                : std::max(fit.max_temperature_c, sample.temperature_c);
  }
  std::optional<std::vector<solver::FerrarisSection>> sections;
  if (request.intervals_s.empty()) sections = labelled_sections(r);
  if (sections) {
    if (fit.terms != TableFreeTerms{}) {
      throw core::InputError(
          "model", fmt::format("run {} is a labelled Ferraris session: six holds and three "
                               "turns leave no redundancy for {} (fit it without; the holds' "
                               "redundancy is spent on the placement error)",
                               run, table_free_model_text(fit.terms)));
    }
    fit.method = "ferraris";
    solver::FerrarisOptions options;
    options.gravity_mps2 = fit.gravity_mps2;
    options.turn_sign = solver::TurnSign::kDetect;
    fit.ferraris = solver::calibrate_ferraris(r.samples, *sections, options);
  } else {
    fit.method = "gravity_norm";
    fit.poses = poses_of(run, fit.device, std::move(r), request);
    calibrate_poses(fit);
  }
  if (!request.history_command.empty()) {
    fit.history_id = store::record_fit(db, table_free_history_record(fit, request.history_command));
  }
  return fit;
}

std::vector<solver::TriadEstimate> table_free_parameters(const TableFreeFit& fit) {
  if (fit.ferraris) return fit.ferraris->parameters;
  std::vector<solver::TriadEstimate> all;
  if (fit.accel) all = fit.accel->parameters;
  if (fit.gyro) all.insert(all.end(), fit.gyro->parameters.begin(), fit.gyro->parameters.end());
  return all;
}

TableFreeQuality table_free_quality(const TableFreeFit& fit) {
  TableFreeQuality q;
  for (const auto& e : table_free_parameters(fit)) {
    if (e.status == solver::EstimateStatus::kEstimated) ++q.parameters;
  }
  if (fit.ferraris) {
    // Six holds against 12 unknowns of the accelerometers leave 6 degrees of freedom; the
    // turns none (nine readings, nine gyro unknowns besides the bias).
    q.chi2 = fit.ferraris->accel_chi2;
    q.dof = fit.ferraris->accel_dof;
    q.rms_norm_residual_mps2 = fit.ferraris->norm_rms_residual_mg * kMgInMps2;
  } else if (fit.accel && fit.gyro) {
    q.chi2 = fit.accel->chi2 + fit.gyro->chi2;
    q.dof = fit.accel->dof + fit.gyro->dof;
    q.rms_norm_residual_mps2 = fit.accel->rms_residual_mg * kMgInMps2;
    q.rms_turn_residual_deg = fit.gyro->rms_residual_deg;
    if (fit.accel->dof > 0)
      q.accel_chi2_per_dof_noise_model = fit.accel->chi2_noise_model / fit.accel->dof;
  }
  q.chi2_per_dof = q.dof > 0 ? q.chi2 / q.dof : std::nan("");
  return q;
}

store::FitRecord table_free_history_record(const TableFreeFit& fit, const std::string& command) {
  const TableFreeQuality q = table_free_quality(fit);
  store::FitRecord r;
  r.run = fit.run;
  r.device = fit.device;
  r.command = command;
  r.model = table_free_model_text(fit.terms);
  r.sensors = "both";
  r.parameters = q.parameters;
  if (q.dof > 0) r.chi2_dof = q.chi2_per_dof;
  r.rms_accel_mps2 = q.rms_norm_residual_mps2;
  r.rms_turn_deg = q.rms_turn_residual_deg;
  return r;
}

nlohmann::json to_json(const TableFreePoses& poses) {
  return {{"run", poses.run},
          {"device", poses.device},
          {"given", poses.given},
          {"samples", poses.samples.size()},
          {"detection", solver::static_detection_to_json(poses.detection)}};
}

nlohmann::json to_json(const TableFreeFit& fit) {
  const TableFreeQuality q = table_free_quality(fit);
  const nlohmann::json terms = table_free_model_terms(fit.terms);
  const nlohmann::json chi2_dof = q.dof > 0 ? nlohmann::json(q.chi2_per_dof) : nlohmann::json();
  nlohmann::json j = {{"run", fit.run},
                      {"device", fit.device},
                      {"method", fit.method},
                      {"model", terms},
                      {"notes", fit.notes},
                      {"gravity_mps2", fit.gravity_mps2},
                      {"earth_rate_modelled", fit.gyro && fit.gyro->earth_rate_modelled},
                      {"frame", solver::kAccelTriadFrameText},
                      {"chi2_dof", chi2_dof},
                      {"dof", q.dof}};
  // Every parameter with its status, and the undetermined ones again as a fit lists them.
  const std::vector<solver::TriadEstimate> estimates = table_free_parameters(fit);
  j["parameters"] = solver::triad_estimates_to_json(estimates);
  nlohmann::json unidentifiable = nlohmann::json::array();
  for (const auto& e : estimates) {
    if (e.status != solver::EstimateStatus::kUndetermined) continue;
    unidentifiable.push_back(
        {{"name", e.name}, {"reason", "the poses and turns of this run do not determine it"}});
  }
  j["unidentifiable"] = unidentifiable;
  j["quality"] = {
      {"chi2", q.chi2},
      {"dof", q.dof},
      {"chi2_per_dof", chi2_dof},
      {"parameters", q.parameters},
      {"rms_norm_residual_mps2", q.rms_norm_residual_mps2},
      {"rms_turn_residual_deg",
       q.rms_turn_residual_deg ? nlohmann::json(*q.rms_turn_residual_deg) : nlohmann::json()}};
  if (fit.history_id) j["history_id"] = *fit.history_id;
  if (fit.poses) j["poses"] = to_json(*fit.poses);
  if (fit.accel) j["accel"] = solver::gravity_norm_to_json(*fit.accel);
  if (fit.gyro) j["gyro"] = solver::gyro_integration_to_json(*fit.gyro);
  if (fit.ferraris) j["ferraris"] = solver::ferraris_to_json(*fit.ferraris);
  return j;
}

}  // namespace calstand::analysis

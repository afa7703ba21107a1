// The diagnosis of a run without a table: the model as given, where it fails, and each optional
// term added in turn.
#include "analysis/table_free_diagnose.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>

#include "core/error.hpp"
#include "core/error_terms.hpp"
#include "core/site.hpp"

namespace calstand::analysis {
namespace {

// A sensor's fit agrees with its noise model up to this chi2/dof (the table diagnosis' figure).
constexpr double kExplainedChi2Dof = 1.5;
// A term is recommended on strong evidence only: BIC lower by more than 10 and an F-test p
// below 1e-3 (a table-free run has tens of residuals, not hundreds: 1e-6 would need an effect
// far above the noise before it could be found at all).
constexpr double kStrongDeltaBic = -10.0;
constexpr double kStrongPValue = 1e-3;
// The worst poses and turns listed.
constexpr std::size_t kWorstShown = 5;

// One sensor's fit quality: chi2 against its noise model, degrees of freedom, residuals.
struct SensorFit {
  double chi2 = 0.0;
  int dof = 0;
  int residuals = 0;  ///< n of the BIC
  std::string residual_text;
};

SensorFit sensor_fit(const TableFreeFit& fit, const std::string& sensor) {
  SensorFit s;
  if (sensor == "accel") {
    s.chi2 = fit.accel->chi2;
    s.dof = fit.accel->dof;
    s.residuals = static_cast<int>(fit.accel->poses.size());
    s.residual_text = fmt::format("|f| - g rms {:.3g} mg", fit.accel->rms_residual_mg);
  } else {
    s.chi2 = fit.gyro->chi2;
    s.dof = fit.gyro->dof;
    s.residuals = 2 * static_cast<int>(fit.gyro->turns.size());  // two components per turn
    s.residual_text =
        fmt::format("gravity direction after the turns {:.3g} deg rms", fit.gyro->rms_residual_deg);
  }
  return s;
}

std::string sensor_of(const std::string& term) {
  return term.rfind("gyro_", 0) == 0 ? "gyro" : "accel";
}

double chi2_per_dof(const SensorFit& s) { return s.dof > 0 ? s.chi2 / s.dof : std::nan(""); }

std::vector<TableFreeOutlier> worst_of(const TableFreeFit& fit) {
  std::vector<TableFreeOutlier> out;
  if (fit.accel) {
    // Each pose against its white noise and the wander its noise model found (RMS over poses).
    const double wander_mg = fit.accel->noise.pose_sigma / kMgInMps2;
    for (std::size_t k = 0; k < fit.accel->poses.size(); ++k) {
      const auto& p = fit.accel->poses[k];
      const double sigma = std::hypot(p.sigma_mg, wander_mg);
      if (!(sigma > 0.0)) continue;
      out.push_back({fmt::format("pose {}", p.interval), p.start_s, p.end_s, p.residual_mg, "mg",
                     p.residual_mg / sigma});
    }
  }
  if (fit.gyro) {
    for (const auto& t : fit.gyro->turns) {
      if (!(t.sigma_deg > 0.0)) continue;
      // The residual is an angle across gravity with two components of sigma_deg each, scaled
      // as the fit scaled the gyro sigmas (the turns' own scatter over the white noise).
      const double sigma = std::sqrt(2.0) * t.sigma_deg * fit.gyro->sigma_scale;
      out.push_back({fmt::format("turn {} -> {}", t.from_interval, t.to_interval), t.start_s,
                     t.end_s, t.residual_deg, "deg", t.residual_deg / sigma});
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return std::abs(a.z) > std::abs(b.z); });
  if (out.size() > kWorstShown) out.resize(kWorstShown);
  return out;
}

TableFreeCandidate judge(const std::string& term, const TableFreeFit& before,
                         const TableFreeFit& after) {
  TableFreeCandidate c;
  c.term = term;
  c.sensor = sensor_of(term);
  const SensorFit b = sensor_fit(before, c.sensor);
  const SensorFit a = sensor_fit(after, c.sensor);
  c.added_parameters = b.dof - a.dof;
  c.chi2_before = b.chi2;
  c.chi2_after = a.chi2;
  c.dof_after = a.dof;
  c.chi2_per_dof_before = chi2_per_dof(b);
  c.chi2_per_dof_after = chi2_per_dof(a);
  c.residual_before = b.residual_text;
  c.residual_after = a.residual_text;
  if (const auto* info = core::find_error_term(term)) c.effect = std::string(info->effect);
  if (c.added_parameters > 0 && a.dof > 0 && a.chi2 > 0.0) {
    const double F = ((b.chi2 - a.chi2) / c.added_parameters) / (a.chi2 / a.dof);
    const boost::math::fisher_f_distribution<double> dist(c.added_parameters, a.dof);
    c.p_value = F > 0.0 ? boost::math::cdf(boost::math::complement(dist, F)) : 1.0;
  }
  // BIC with the residual variance profiled out (a Gaussian likelihood whose scale is unknown,
  // as the noise model's may be off by a factor): n ln(chi2_after / chi2_before) + k ln n.
  const int n = std::max(1, b.residuals);
  if (a.chi2 > 0.0 && b.chi2 > 0.0) {
    c.delta_bic = n * std::log(a.chi2 / b.chi2) + c.added_parameters * std::log(n);
  }
  return c;
}

// The accelerometers against their own noise model (chi2/dof, near 1 when the model and the
// noise model describe the poses), in words.
std::string accel_noise_text(const solver::GravityNormResult& a) {
  return fmt::format(
      "the poses scatter with chi2/dof {:.3g} against their noise model ({}; {:.3g} against the "
      "white noise alone)",
      a.dof > 0 ? a.chi2_noise_model / a.dof : 0.0, a.noise.description, a.chi2_per_dof);
}

// The gyros against their turns' noise model (solver/gyro_integration.hpp: the gyro's white
// noise and bias wander over each turn, the pose means' accel noise and wander, the referral of
// the holds with the hand's sway), in words.
std::string gyro_noise_text(const solver::GyroIntegrationResult& g) {
  return fmt::format(
      "the turns scatter with chi2/dof {:.3g} against their noise model (gyro white noise and "
      "bias wander over each turn, the poses' accel noise and wander, the hand's sway in the "
      "holds){}",
      g.chi2_per_dof,
      g.earth_rate_modelled ? std::string()
                            : std::string("; the Earth rate is not modelled (no site latitude)"));
}

std::string advice_of(const TableFreeDiagnosis& d) {
  if (d.fit.ferraris) {
    return fmt::format(
        "a labelled Ferraris session (six holds, three turns) has no redundancy for further "
        "terms: its six degrees of freedom are spent on the placement of the holds "
        "(accelerometer chi2/dof {:.3g} with the placement, {:.3g} taken as exact). To test "
        "more effects, record a session turned by hand between 20 or more poses.",
        d.fit.ferraris->accel_chi2_per_dof, d.fit.ferraris->accel_chi2_per_dof_naive);
  }
  const std::string noise =
      accel_noise_text(*d.fit.accel) + "; " + gyro_noise_text(*d.fit.gyro) + ".";
  if (!d.recommended.empty()) {
    const TableFreeCandidate& c = d.candidates.front();
    return fmt::format(
        "add {}: it lowers the {} chi2/dof from {:.3g} to {:.3g} (F-test p = {:.2g}, delta BIC "
        "{:.1f}; {} -> {}). {}. Then diagnose again.",
        c.term, c.sensor, c.chi2_per_dof_before, c.chi2_per_dof_after, c.p_value, c.delta_bic,
        c.residual_before, c.residual_after, c.effect);
  }
  std::string best;
  if (!d.candidates.empty()) {
    const TableFreeCandidate& c = d.candidates.front();
    best = c.p_value < kStrongPValue
               ? fmt::format(
                     " The best candidate, {}, lowers chi2/dof from {:.3g} to {:.3g} "
                     "(p = {:.2g}) but not by enough for its {} parameters (delta BIC "
                     "{:.1f}).",
                     c.term, c.chi2_per_dof_before, c.chi2_per_dof_after, c.p_value,
                     c.added_parameters, c.delta_bic)
               : fmt::format(" No candidate is supported by the data (best: {}, p = {:.2g}).",
                             c.term, c.p_value);
  }
  if (d.explained) return "the model fits: " + noise + best;
  return "the poses scatter more than their noise model allows: " + noise + best +
         " Look at the worst poses and turns: a pose held while moving, a turn whose grip "
         "slipped or that starts before the pose settled; effects that need a table or a "
         "chamber (thermal terms, lever arm) cannot be told apart here.";
}

}  // namespace

TableFreeDiagnosis diagnose_table_free(store::Database& db, std::int64_t run,
                                       const TableFreeFitRequest& request) {
  TableFreeDiagnosis d;
  d.fit = table_free_fit(db, run, request);
  d.worst = worst_of(d.fit);
  // The Earth rate is physics, not a candidate: modelled in every fit with a latitude.
  d.untestable.push_back(
      d.fit.ferraris ? "earth_rate: the heading of the holds is not known (the Ferraris method "
                       "leaves it in the gyro bias)"
      : d.fit.gyro && d.fit.gyro->earth_rate_modelled
          ? "earth_rate: no candidate, modelled in every fit (vertical part from the site "
            "latitude, the initial rest's heading fitted)"
          : "earth_rate: the run has no site latitude (and the heading of the poses is not "
            "known): not modelled");
  for (const std::string& term : table_free_optional_terms()) {
    if (has_table_free_term(request.terms, term)) continue;
    if (d.fit.ferraris) {
      d.untestable.push_back(term + ": a Ferraris session has no redundancy for it");
      continue;
    }
    // The candidates are tries on the samples and poses already read, not fits the user asked
    // for: nothing is recorded.
    TableFreeFit after;
    try {
      after = refit_table_free(d.fit, with_table_free_term(request.terms, term));
    } catch (const core::InputError& e) {
      d.untestable.push_back(fmt::format("{}: {}", term, e.what()));
      continue;
    }
    TableFreeCandidate c = judge(term, d.fit, after);
    if (c.added_parameters <= 0) {
      d.untestable.push_back(term + ": these poses and turns do not determine it");
      continue;
    }
    d.candidates.push_back(std::move(c));
  }
  std::stable_sort(d.candidates.begin(), d.candidates.end(),
                   [](const auto& a, const auto& b) { return a.delta_bic < b.delta_bic; });

  if (d.fit.ferraris) {
    d.explained = d.fit.ferraris->accel_chi2_per_dof <= kExplainedChi2Dof;
  } else {
    if (!d.candidates.empty() && d.candidates.front().delta_bic < kStrongDeltaBic &&
        d.candidates.front().p_value < kStrongPValue) {
      d.recommended = d.candidates.front().term;
    }
    // Each sensor is judged against its noise model (a wandering bias is noise, not a missing
    // effect): the accelerometers' pose means by REML, the turns by theirs.
    const solver::GravityNormResult& a = *d.fit.accel;
    const solver::GyroIntegrationResult& g = *d.fit.gyro;
    d.explained = d.recommended.empty() && a.dof > 0 &&
                  a.chi2_noise_model / a.dof <= kExplainedChi2Dof && g.dof > 0 &&
                  g.chi2_per_dof <= kExplainedChi2Dof;
  }
  d.advice = advice_of(d);
  return d;
}

nlohmann::json to_json(const TableFreeDiagnosis& d) {
  const nlohmann::json fit = to_json(d.fit);
  nlohmann::json j = {{"run", d.fit.run},
                      {"device", d.fit.device},
                      {"method", d.fit.method},
                      {"model", fit["model"]},
                      {"fit", fit}};
  nlohmann::json worst = nlohmann::json::array();
  for (const auto& w : d.worst) {
    worst.push_back({{"what", w.what},
                     {"start_s", w.start_s},
                     {"end_s", w.end_s},
                     {"residual", w.residual},
                     {"unit", w.unit},
                     {"z", w.z}});
  }
  j["worst"] = worst;
  nlohmann::json candidates = nlohmann::json::array();
  for (const auto& c : d.candidates) {
    candidates.push_back({{"term", c.term},
                          {"sensor", c.sensor},
                          {"added_parameters", c.added_parameters},
                          {"chi2_before", c.chi2_before},
                          {"chi2_after", c.chi2_after},
                          {"dof_after", c.dof_after},
                          {"chi2_dof_before", c.chi2_per_dof_before},
                          {"chi2_dof_after", c.chi2_per_dof_after},
                          {"p_value", c.p_value},
                          {"delta_bic", c.delta_bic},
                          {"residual_before", c.residual_before},
                          {"residual_after", c.residual_after},
                          {"explanation", c.effect}});
  }
  j["candidates"] = candidates;
  j["untestable"] = d.untestable;
  j["explained"] = d.explained;
  j["recommended"] = d.recommended;
  j["advice"] = d.advice;
  return j;
}

}  // namespace calstand::analysis

#include "report/report_data.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>

#include "analysis/fit_history.hpp"
#include "analysis/noise_json.hpp"
#include "analysis/noise_run.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "report/static_report.hpp"
#include "solver/groups.hpp"
#include "solver/signals.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

using ConditionField = std::string solver::StepConditions::*;
constexpr std::array<std::pair<const char*, ConditionField>, 6> kConditionKinds = {{
    {"plateau", &solver::StepConditions::plateau},
    {"orientation", &solver::StepConditions::orientation},
    {"rate", &solver::StepConditions::rate},
    {"direction", &solver::StepConditions::direction},
    {"axis", &solver::StepConditions::axis},
    {"time", &solver::StepConditions::time},
}};

std::vector<std::string> split_terms(const std::string& model) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= model.size()) {
    const std::size_t end = std::min(model.find(',', start), model.size());
    std::string t = model.substr(start, end - start);
    t.erase(0, t.find_first_not_of(" \t"));
    t.erase(t.find_last_not_of(" \t") + 1);
    if (!t.empty()) out.push_back(t);
    start = end + 1;
  }
  return out;
}

StepGrouping grouping_by(const std::vector<solver::StepConditions>& conditions,
                         const std::string& kind, ConditionField field) {
  StepGrouping g;
  g.kind = kind;
  for (const auto& c : conditions) {
    g.of_step.push_back(c.*field);
    if (std::find(g.values.begin(), g.values.end(), c.*field) == g.values.end()) {
      g.values.push_back(c.*field);
    }
  }
  return g;
}

// The noise of the static capture the stability analysis reads (so that the curve and its
// figures agree), made from the samples the fit has read already: a long capture is read from
// the database once, not again for the Allan plot and again for the stability figures. Returns
// that capture's noise at the octave averaging times the stability's rules are made for
// (stability_of()), for run_datasheet_analyses(); none when the capture is not held.
std::optional<solver::RunNoise> analyse_noise(
    store::Database& db, ReportData& r, const solver::RunData& data,
    const std::vector<DatasheetApplicability>& applicability) {
  for (const auto& s : r.steps) {
    if (s.is_static) r.longest_static_s = std::max(r.longest_static_s, s.duration_s);
  }
  const auto stability =
      std::find_if(applicability.begin(), applicability.end(),
                   [](const auto& a) { return a.kind == DatasheetKind::kStability; });
  if (!stability->applies && r.procedure != "static-allan") {
    r.noise_note =
        long_enough_for_noise(r.longest_static_s)
            ? fmt::format("no Allan deviation: {}", stability->evidence)
            : fmt::format(
                  "not a static run: its longest static step lasts {:.0f} s; the Allan deviation "
                  "is shown for runs with a static record of {:.0f} s or more (e.g. the "
                  "static-allan procedure)",
                  r.longest_static_s, kMinNoiseRecordS);
    return std::nullopt;
  }
  solver::RunNoiseOptions options;
  options.device = r.device;
  options.step = stability->step;
  options.allan.taus = solver::TauSet::parse("dense");
  try {
    const std::size_t step = solver::choose_noise_step(db, r.request.run, stability->step);
    const auto held = std::find_if(data.steps.begin(), data.steps.end(),
                                   [&](const store::StepData& d) { return d.step.index == step; });
    if (held == data.steps.end()) {
      r.noise = solver::analyse_run_noise(db, r.request.run, options);  // says why it has none
    } else if (!r.fitted()) {
      // A record at rest and nothing else (a static-allan run): the page of such a record.
      std::optional<solver::NoiseIdOptions> noise_id;
      if (r.request.noise_model) {
        noise_id.emplace();
      }
      auto record = std::make_shared<StaticRecordNoise>(analyse_static_record(
          held->samples, r.request.run, r.device, step, held->step.label, noise_id));
      r.noise = record->noise;
      r.static_record = std::move(record);
    } else {
      r.noise = solver::analyse_noise_samples(held->samples, options);
      r.noise->run = r.request.run;
      r.noise->device = r.device;
      r.noise->step = step;
      r.noise->step_label = held->step.label;
    }
    if (held == data.steps.end() || !stability->applies) return std::nullopt;
    solver::RunNoiseOptions octave;
    octave.device = r.device;
    solver::RunNoise at_octaves = solver::analyse_noise_samples(held->samples, octave);
    at_octaves.run = r.request.run;
    at_octaves.device = r.device;
    at_octaves.step = step;
    at_octaves.step_label = held->step.label;
    return at_octaves;
  } catch (const core::InputError& e) {
    r.noise_note = fmt::format("no Allan deviation: {}", e.what());
  }
  return std::nullopt;
}

// The warm-up capture in bins of the analysis's own width, less the settled values, and the fit.
WarmupSeries warmup_series(store::Database& db, const ReportData& r, const WarmupAnalysis& w) {
  constexpr double kDegPerHPerDegPerS = 3600.0;
  WarmupSeries out;
  std::vector<double> temperature_c;
  store::for_each_step_data(db, r.request.run, r.device, [&](const store::StepData& data) {
    if (data.step.index != w.step || data.samples.empty() || !(w.bin_s > 0.0)) return;
    const double t0 = data.samples.front().receive_time_s;
    const auto bins = static_cast<std::size_t>(w.duration_s / w.bin_s) + 1;
    std::vector<double> t_sum(bins, 0.0);
    std::vector<double> temperature_sum(bins, 0.0);
    std::vector<std::size_t> count(bins, 0);
    std::array<std::vector<double>, 6> sum;
    for (auto& v : sum) v.assign(bins, 0.0);
    for (const core::ImuSample& s : data.samples) {
      const double t = s.receive_time_s - t0;
      const auto b = std::min(bins - 1, static_cast<std::size_t>(std::max(0.0, t / w.bin_s)));
      t_sum[b] += t;
      temperature_sum[b] += s.temperature_c;
      ++count[b];
      for (int c = 0; c < 3; ++c) {
        sum[c][b] += s.gyro_dps[c] * kDegPerHPerDegPerS;
        sum[c + 3][b] += s.accel_mps2[c] / core::kMicroGToMps2;
      }
    }
    for (std::size_t b = 0; b < bins; ++b) {
      if (count[b] == 0) continue;
      const auto n = static_cast<double>(count[b]);
      out.t_s.push_back(t_sum[b] / n);
      temperature_c.push_back(temperature_sum[b] / n);
      for (std::size_t c = 0; c < 6; ++c) {
        out.deviation[c].push_back(sum[c][b] / n - w.channels[c].settled);
      }
    }
  });
  for (std::size_t c = 0; c < 6 && !out.t_s.empty(); ++c) {
    const ChannelWarmup& ch = w.channels[c];
    if (!ch.resolved || !(ch.time_constant_s > 0.0)) continue;
    std::vector<double> transient;
    for (const double t : out.t_s)
      transient.push_back(ch.amplitude * std::exp(-t / ch.time_constant_s));
    out.fitted[c] = transient;
    if (!ch.temperature_term) continue;
    // The analysis keeps its temperature coefficient k to itself. At its least-squares optimum
    // k is also the least-squares k with the settled value and the transient held, which these
    // bins (the same as the analysis's) give back: k = sum(res * dT) / sum(dT^2).
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < out.t_s.size(); ++i) {
      const double dt = temperature_c[i] - temperature_c.back();
      num += (out.deviation[c][i] - transient[i]) * dt;
      den += dt * dt;
    }
    const double k = den > 0.0 ? num / den : 0.0;
    for (std::size_t i = 0; i < out.t_s.size(); ++i) {
      out.fitted[c][i] += k * (temperature_c[i] - temperature_c.back());
    }
  }
  return out;
}

// Completed steps of each kind, in order of first appearance.
std::vector<std::pair<std::string, std::size_t>> count_step_kinds(
    const std::vector<store::StepRecord>& steps) {
  std::vector<std::pair<std::string, std::size_t>> out;
  for (const auto& s : steps) {
    if (s.status != store::StepStatus::kCompleted) continue;
    auto it =
        std::find_if(out.begin(), out.end(), [&](const auto& k) { return k.first == s.kind; });
    if (it == out.end()) {
      out.emplace_back(s.kind, 1);
    } else {
      ++it->second;
    }
  }
  return out;
}

}  // namespace

std::size_t StepGrouping::value_index(std::size_t step) const {
  const auto it = std::find(values.begin(), values.end(), of_step.at(step));
  return static_cast<std::size_t>(it - values.begin());
}

std::vector<std::string> history_labels(const std::vector<store::FitRecord>& fits) {
  std::vector<std::string> labels;
  std::vector<std::string> before;
  for (std::size_t i = 0; i < fits.size(); ++i) {
    const std::vector<std::string> terms = split_terms(fits[i].model);
    std::string label;
    if (i == 0) {
      label = terms.size() <= 2 ? fits[i].model : fmt::format("{} terms", terms.size());
    } else {
      for (const auto& t : terms) {
        if (std::find(before.begin(), before.end(), t) == before.end()) label += " +" + t;
      }
      for (const auto& t : before) {
        if (std::find(terms.begin(), terms.end(), t) == terms.end()) label += " -" + t;
      }
      label = label.empty() ? std::string("same model") : label.substr(1);
    }
    if (label.size() > 40) label = label.substr(0, 37) + "...";
    labels.push_back(fmt::format("#{} {}", fits[i].id, label));
    before = terms;
  }
  return labels;
}

StepGrouping choose_grouping(const solver::Diagnosis& d,
                             const std::vector<solver::StepSummary>& steps) {
  const std::vector<solver::StepConditions> conditions = solver::step_conditions(steps);
  for (const auto& group : d.groups) {
    const std::string kind = group.group.substr(0, group.group.find(':'));
    for (const auto& [name, field] : kConditionKinds) {
      if (kind != name) continue;
      StepGrouping g = grouping_by(conditions, name, field);
      if (g.values.size() > 1) return g;
    }
  }
  for (const auto& [name, field] : kConditionKinds) {
    StepGrouping g = grouping_by(conditions, name, field);
    if (g.values.size() > 1) return g;
  }
  StepGrouping all;
  all.kind = "steps";
  all.of_step.assign(steps.size(), "all steps");
  all.values = {"all steps"};
  return all;
}

std::optional<std::vector<double>> signal_series(const std::vector<solver::StepSummary>& steps,
                                                 const std::string& signal) {
  std::string name = signal;
  auto member = &solver::StepSummary::signals;
  if (name.starts_with("abs(") && name.ends_with(")")) {
    name = name.substr(4, name.size() - 5);
    member = &solver::StepSummary::signals_abs;
  } else if (name.ends_with("^2")) {
    name.resize(name.size() - 2);
    member = &solver::StepSummary::signals_sq;
  }
  const auto& names = solver::signal_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  const auto k = static_cast<std::size_t>(it - names.begin());
  std::vector<double> out;
  for (const auto& s : steps) out.push_back((s.*member)[k]);
  return out;
}

std::string single_condition_reason(const std::vector<solver::StepSummary>& steps) {
  const std::vector<solver::StepConditions> conditions = solver::step_conditions(steps);
  if (conditions.empty()) return "";
  const solver::StepConditions& first = conditions.front();
  for (const auto& c : conditions) {
    if (c.plateau != first.plateau || c.orientation != first.orientation || c.rate != first.rate ||
        c.direction != first.direction || c.axis != first.axis) {
      return "";
    }
  }
  return fmt::format(
      "{} one condition ({}, {}, {}): {} one measurement, which determines no error model "
      "(an error model needs steps that differ in pose, rate or temperature)",
      conditions.size() == 1 ? std::string("its one step is")
                             : fmt::format("all {} of its steps are", conditions.size()),
      first.orientation, first.rate, first.plateau,
      conditions.size() == 1 ? "it is" : "their means repeat");
}

ReportData gather_report(store::Database& db, const ReportRequest& request) {
  ReportData r;
  r.request = request;
  const solver::Model model = solver::Model::parse(request.model, request.customs);
  solver::FitOptions options;
  options.rows = parse_sensor_rows(request.sensor);
  const solver::RunData data = load_fit_data(db, request.run, request.device);
  r.procedure = data.setup.procedure_name;
  r.device = data.setup.device;
  const store::RunRecord record = store::RunStore(db).load_run(request.run);
  r.run = record.summary;
  r.step_kinds = count_step_kinds(record.steps);
  r.steps = solver::summarize_steps(data, model);
  r.no_fit_reason = single_condition_reason(r.steps);
  const auto applicability = datasheet_applicability(record.steps);
  const auto power_cycled = std::find_if(
      applicability.begin(), applicability.end(),
      [](const auto& a) { return a.kind == DatasheetKind::kRepeatability && a.applies; });
  if (r.fitted() && power_cycled != applicability.end()) {
    // Each power-up has its own turn-on bias (and scale): one error model cannot hold steps
    // recorded across power cycles, and its chi2 would read the repeatability as a misfit.
    r.no_fit_reason = fmt::format(
        "the unit was switched off and on between its recorded steps ({}): each power-up has "
        "its own turn-on bias, so no one error model holds the run; its figure is the "
        "repeatability",
        power_cycled->evidence);
  }
  if (r.fitted()) {
    try {
      solver::DiagnoseOptions diagnose_options;
      if (request.noise_run) {
        diagnose_options.noise.known_wander =
            noise_run_wander(db, *request.noise_run, request.device, data);
      }
      r.diagnosis = solver::diagnose(data, model, options, diagnose_options);
    } catch (const core::InputError& e) {
      // The model asks more of the run than its steps determine: the page says so.
      r.no_fit_reason = fmt::format("the run does not determine the model: {}", e.what());
    }
  }
  if (r.fitted()) {
    record_history(db, request.run, r.device, "report", model, r.diagnosis.fit, request.sensor);
    for (auto& f : store::fit_history(db, request.run)) {
      if (f.device == r.device) r.history.push_back(std::move(f));
    }
    r.history_labels = history_labels(r.history);
    r.grouping = choose_grouping(r.diagnosis, r.steps);
  }
  const std::optional<solver::RunNoise> stability_noise = analyse_noise(db, r, data, applicability);
  DatasheetOptions datasheet;
  if (stability_noise) datasheet.stability_noise = &*stability_noise;
  r.datasheet = run_datasheet_analyses(db, request.run, r.device, datasheet);
  if (r.datasheet.warmup) r.warmup_series = warmup_series(db, r, *r.datasheet.warmup);
  return r;
}

}  // namespace calstand::analysis

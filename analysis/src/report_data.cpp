#include "analysis/report_data.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <set>
#include <utility>

#include "analysis/fit_history.hpp"
#include "analysis/noise_json.hpp"
#include "core/error.hpp"
#include "solver/groups.hpp"
#include "solver/signals.hpp"

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

void analyse_noise(store::Database& db, ReportData& r) {
  for (const auto& s : r.steps) {
    if (s.is_static) r.longest_static_s = std::max(r.longest_static_s, s.duration_s);
  }
  if (!long_enough_for_noise(r.longest_static_s) && r.procedure != "static-allan") {
    r.noise_note = fmt::format(
        "not a static run: its longest static step lasts {:.0f} s; the Allan deviation is shown "
        "for runs with a static record of {:.0f} s or more (e.g. the static-allan procedure)",
        r.longest_static_s, kMinNoiseRecordS);
    return;
  }
  solver::RunNoiseOptions options;
  options.device = r.device;
  options.allan.taus = solver::TauSet::parse("dense");
  try {
    r.noise = solver::analyse_run_noise(db, r.request.run, options);
  } catch (const core::InputError& e) {
    r.noise_note = fmt::format("no Allan deviation: {}", e.what());
  }
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

ReportData gather_report(store::Database& db, const ReportRequest& request) {
  ReportData r;
  r.request = request;
  const solver::Model model = solver::Model::parse(request.model, request.customs);
  const solver::RunData data = load_fit_data(db, request.run, request.device);
  r.procedure = data.setup.procedure_name;
  r.device = data.setup.device;
  solver::FitOptions options;
  options.rows = parse_sensor_rows(request.sensor);
  r.diagnosis = solver::diagnose(data, model, options);
  record_history(db, request.run, r.device, "report", model, r.diagnosis.fit, request.sensor);
  for (auto& f : store::fit_history(db, request.run)) {
    if (f.device == r.device) r.history.push_back(std::move(f));
  }
  r.history_labels = history_labels(r.history);
  r.steps = solver::summarize_steps(data, model);
  r.grouping = choose_grouping(r.diagnosis, r.steps);
  analyse_noise(db, r);
  return r;
}

}  // namespace calstand::analysis

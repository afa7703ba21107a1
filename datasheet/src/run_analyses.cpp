#include "datasheet/run_analyses.hpp"

#include <fmt/format.h>

#include <map>
#include <utility>

#include "analysis/noise_json.hpp"
#include "analysis/run_model.hpp"
#include "core/error.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

bool completed(const store::StepRecord& s) { return s.status == store::StepStatus::kCompleted; }

// A capture's length on the station clock, or as commanded when the clock was not recorded.
double capture_length_s(const store::StepRecord& s) {
  return s.started_clock_s && s.ended_clock_s ? *s.ended_clock_s - *s.started_clock_s
                                              : s.commanded.value("duration_s", 0.0);
}

std::string step_name(const store::StepRecord& s) {
  return fmt::format("step {} ({})", s.index, s.label);
}

struct PowerUps {
  std::size_t with_captures = 0;  ///< power-ups followed by a completed capture
  std::size_t total = 0;
  /// Captures that start at a power-up (the next step after a power-on without settle time).
  std::vector<const store::StepRecord*> at_power_on;
};

PowerUps power_ups(const std::vector<store::StepRecord>& steps) {
  PowerUps out;
  bool powered = false;
  bool counted = false;
  const store::StepRecord* just_on = nullptr;  // the power-on step right before this one
  for (const auto& s : steps) {
    const store::StepRecord* previous_on = just_on;
    just_on = nullptr;
    if (!completed(s)) continue;
    if (s.kind == "power") {
      powered = s.commanded.value("power", "") == "on";
      counted = false;
      if (powered) {
        ++out.total;
        just_on = &s;
      }
      continue;
    }
    if (s.kind != "capture" || !powered) continue;
    if (!counted) ++out.with_captures, counted = true;
    if (previous_on && previous_on->commanded.value("settle_s", 0.0) <= kPowerOnCaptureMaxSettleS) {
      out.at_power_on.push_back(&s);
    }
  }
  return out;
}

DatasheetApplicability repeatability_of(const PowerUps& p) {
  DatasheetApplicability a{DatasheetKind::kRepeatability, false, "", std::nullopt};
  a.applies = p.with_captures >= 2;
  if (a.applies) {
    a.evidence = fmt::format("{} power-ups, each followed by captures", p.with_captures);
  } else if (p.total == 0) {
    a.evidence = "no power-up (power steps)";
  } else {
    a.evidence = fmt::format(
        "{} power-up(s) followed by a capture; repeatability compares two "
        "or more",
        p.with_captures);
  }
  return a;
}

DatasheetApplicability warmup_of(const PowerUps& p) {
  DatasheetApplicability a{DatasheetKind::kWarmup, false, "", std::nullopt};
  a.applies = !p.at_power_on.empty();
  if (a.applies) {
    a.step = p.at_power_on.front()->index;
    a.evidence = step_name(*p.at_power_on.front()) + " records from a power-up";
  } else {
    a.evidence = "no capture starts at a power-up";
  }
  return a;
}

DatasheetApplicability stability_of(const std::vector<store::StepRecord>& steps,
                                    const PowerUps& p) {
  DatasheetApplicability a{DatasheetKind::kStability, false, "", std::nullopt};
  const store::StepRecord* longest = nullptr;
  std::size_t skipped_warmup = 0;
  for (const auto& s : steps) {
    if (s.kind != "capture" || !completed(s)) continue;
    // A record from power-on holds the warm-up transient: that is not in-run stability.
    if (std::find(p.at_power_on.begin(), p.at_power_on.end(), &s) != p.at_power_on.end()) {
      skipped_warmup += long_enough_for_noise(capture_length_s(s)) ? 1 : 0;
      continue;
    }
    if (!longest || capture_length_s(s) > capture_length_s(*longest)) longest = &s;
  }
  a.applies = longest && long_enough_for_noise(capture_length_s(*longest));
  if (a.applies) {
    a.step = longest->index;
    a.evidence =
        fmt::format("{} records {:.0f} s static", step_name(*longest), capture_length_s(*longest));
    return a;
  }
  a.evidence = longest ? fmt::format(
                             "its longest static capture records {:.0f} s; in-run "
                             "stability needs {:.0f} s or more",
                             capture_length_s(*longest), kMinNoiseRecordS)
                       : std::string("no static capture");
  if (skipped_warmup > 0) a.evidence += " (a record from power-up shows the warm-up instead)";
  return a;
}

DatasheetApplicability hysteresis_of(const std::vector<store::StepRecord>& steps) {
  DatasheetApplicability a{DatasheetKind::kHysteresis, false, "", std::nullopt};
  // Set point -> reached from below / from above with captures there.
  std::map<double, std::pair<bool, bool>> visits;
  std::optional<double> previous;
  std::optional<double> current;
  int direction = 0;  // +1 reached from below, -1 from above, 0 unknown (the first set point)
  std::size_t set_points = 0;
  for (const auto& s : steps) {
    if (!completed(s)) continue;
    if (s.kind == "set_temperature" && s.commanded.contains("target_c")) {
      const double target = s.commanded.value("target_c", 0.0);
      previous = current;
      current = target;
      direction = !previous || *previous == target ? 0 : (*previous < target ? 1 : -1);
      ++set_points;
      continue;
    }
    if (s.kind != "capture" || !current || direction == 0) continue;
    auto& [below, above] = visits[*current];
    (direction > 0 ? below : above) = true;
  }
  std::vector<double> both;
  for (const auto& [t, v] : visits) {
    if (v.first && v.second) both.push_back(t);
  }
  a.applies = !both.empty();
  if (a.applies) {
    a.evidence = fmt::format(
        "a temperature staircase with captures at {} degC reached from "
        "below and from above",
        fmt::join(both, ", "));
  } else {
    a.evidence = set_points < 2 ? std::string("no temperature staircase")
                                : "no set point with captures is reached from both sides";
  }
  return a;
}

DatasheetApplicability bandwidth_of(const std::vector<store::StepRecord>& steps) {
  DatasheetApplicability a{DatasheetKind::kBandwidth, false, "", std::nullopt};
  std::size_t oscillations = 0;
  for (const auto& s : steps) oscillations += s.kind == "oscillate" && completed(s) ? 1 : 0;
  a.applies = oscillations > 0;
  a.evidence = a.applies ? fmt::format("{} oscillate steps", oscillations)
                         : std::string("no oscillate step");
  return a;
}

std::size_t position(DatasheetKind kind) { return static_cast<std::size_t>(kind); }

// Makes one analysis, keeping its refusal of the run's data (not any other error) as the reason
// the figure is missing.
template <typename Analysis, typename Make>
void attempt(DatasheetAnalyses& out, DatasheetKind kind, std::optional<Analysis>& slot, Make make) {
  if (!out.applicability_of(kind).applies) return;
  try {
    slot = make();
  } catch (const core::InputError& e) {
    out.failure[position(kind)] = e.what();
  }
}

}  // namespace

std::string_view to_string(DatasheetKind kind) {
  switch (kind) {
    case DatasheetKind::kRepeatability:
      return "repeatability";
    case DatasheetKind::kWarmup:
      return "warmup";
    case DatasheetKind::kStability:
      return "stability";
    case DatasheetKind::kHysteresis:
      return "hysteresis";
    case DatasheetKind::kBandwidth:
      return "bandwidth";
  }
  return "?";
}

std::string_view title(DatasheetKind kind) {
  switch (kind) {
    case DatasheetKind::kRepeatability:
      return "Bias repeatability";
    case DatasheetKind::kWarmup:
      return "Warm-up";
    case DatasheetKind::kStability:
      return "In-run bias stability";
    case DatasheetKind::kHysteresis:
      return "Thermal hysteresis";
    case DatasheetKind::kBandwidth:
      return "Bandwidth";
  }
  return "?";
}

std::vector<DatasheetApplicability> datasheet_applicability(
    const std::vector<store::StepRecord>& steps) {
  const PowerUps p = power_ups(steps);
  return {repeatability_of(p), warmup_of(p), stability_of(steps, p), hysteresis_of(steps),
          bandwidth_of(steps)};
}

bool DatasheetAnalyses::has_result(DatasheetKind kind) const {
  switch (kind) {
    case DatasheetKind::kRepeatability:
      return repeatability.has_value();
    case DatasheetKind::kWarmup:
      return warmup.has_value();
    case DatasheetKind::kStability:
      return stability.has_value();
    case DatasheetKind::kHysteresis:
      return hysteresis.has_value();
    case DatasheetKind::kBandwidth:
      return bandwidth.has_value();
  }
  return false;
}

const DatasheetApplicability& DatasheetAnalyses::applicability_of(DatasheetKind kind) const {
  return applicability.at(position(kind));
}

const std::string& DatasheetAnalyses::failure_of(DatasheetKind kind) const {
  return failure.at(position(kind));
}

DatasheetAnalyses run_datasheet_analyses(store::Database& db, std::int64_t run,
                                         const std::string& device,
                                         const DatasheetOptions& options) {
  DatasheetAnalyses out;
  out.run = run;
  // Outside the analyses' refusals: a bad run or device is the request's fault.
  out.device = choose_fit_device(db, run, device);
  out.applicability = datasheet_applicability(store::RunStore(db).load_steps(run));
  attempt(out, DatasheetKind::kRepeatability, out.repeatability,
          [&] { return analyse_repeatability(db, run, out.device); });
  attempt(out, DatasheetKind::kWarmup, out.warmup, [&] {
    return analyse_warmup(db, run, out.device, out.applicability_of(DatasheetKind::kWarmup).step,
                          options.warmup_band_deg_per_h, options.warmup_band_ug);
  });
  attempt(out, DatasheetKind::kStability, out.stability, [&] {
    const std::optional<std::size_t> step = out.applicability_of(DatasheetKind::kStability).step;
    const solver::RunNoise* noise = options.stability_noise;
    if (noise && noise->run == run && noise->device == out.device && step && noise->step == *step) {
      return stability_of(*noise);
    }
    return analyse_stability(db, run, out.device, step);
  });
  attempt(out, DatasheetKind::kHysteresis, out.hysteresis,
          [&] { return analyse_hysteresis(db, run, out.device); });
  attempt(out, DatasheetKind::kBandwidth, out.bandwidth,
          [&] { return analyse_bandwidth(db, run, out.device); });
  return out;
}

nlohmann::json to_json(const DatasheetAnalyses& a) {
  nlohmann::json analyses = nlohmann::json::object();
  nlohmann::json missing = nlohmann::json::object();
  nlohmann::json not_applicable = nlohmann::json::object();
  nlohmann::json evidence = nlohmann::json::object();
  if (a.repeatability) analyses["repeatability"] = to_json(*a.repeatability);
  if (a.warmup) analyses["warmup"] = to_json(*a.warmup);
  if (a.stability) analyses["stability"] = to_json(*a.stability);
  if (a.hysteresis) analyses["hysteresis"] = to_json(*a.hysteresis);
  if (a.bandwidth) analyses["bandwidth"] = to_json(*a.bandwidth);
  for (const DatasheetApplicability& ap : a.applicability) {
    const std::string kind(to_string(ap.kind));
    if (!ap.applies) {
      not_applicable[kind] = ap.evidence;
      continue;
    }
    evidence[kind] = ap.evidence;
    if (!a.failure_of(ap.kind).empty()) missing[kind] = a.failure_of(ap.kind);
  }
  return {{"run", a.run},
          {"device", a.device},
          {"analyses", analyses},
          {"missing", missing},
          {"not_applicable", not_applicable},
          {"evidence", evidence}};
}

}  // namespace calstand::analysis

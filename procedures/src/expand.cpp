// Expansion: loops unrolled, references resolved, value rules checked, step by step.
#include <fmt/format.h>

#include <cmath>
#include <set>

#include "parameters.hpp"
#include "procedures/pointing.hpp"
#include "procedures/procedure.hpp"
#include "references.hpp"

namespace calstand::procedures {
namespace {

using detail::format_number;
using detail::quote_value;
using nlohmann::json;

constexpr double kDefaultSettleS = 2.0;    // rate steps without settle_s [s]
constexpr double kMaxAbsAngleDeg = 360.0;  // move angles beyond one turn are a typo, not intent
// Oscillations without settle_cycles: two periods, so that the start of the sine (the servo
// catching up, the IMU's output filter) has died out before the record; both settle within a
// small part of a period at the frequencies a bandwidth test uses.
constexpr double kDefaultSettleCycles = 2.0;
constexpr const char* kBodyDirections = "\"+x\", \"-x\", \"+y\", \"-y\", \"+z\", \"-z\"";

class Expander {
 public:
  Expander(std::map<std::string, json> parameters, std::vector<Violation>& out)
      : parameters_(std::move(parameters)), out_(out) {}

  void steps(const json& list, const std::string& path) {
    for (std::size_t i = 0; i < list.size() && !overflow_; ++i) {
      step(list[i], fmt::format("{}[{}]", path, i));
    }
  }

  std::vector<Step> finish() {
    for (std::size_t i = 0; i < steps_.size(); ++i) {
      Step& s = steps_[i];
      s.index = i;
      if (s.kind == StepKind::kRate) {
        const bool next_same_axis = i + 1 < steps_.size() &&
                                    steps_[i + 1].kind == StepKind::kRate &&
                                    steps_[i + 1].axis == s.axis;
        s.rest_after = !next_same_axis;
      }
    }
    return std::move(steps_);
  }

 private:
  // Loop variables (innermost first; they never shadow), then parameters.
  std::optional<json> lookup(const std::string& name) const {
    for (auto it = scope_.rbegin(); it != scope_.rend(); ++it) {
      if (it->first == name) return it->second;
    }
    if (auto it = parameters_.find(name); it != parameters_.end()) return it->second;
    return std::nullopt;
  }

  // Several loop iterations may break one rule in the same way: say it once.
  void add(const std::string& path, std::string message) {
    if (seen_.emplace(path, message).second) out_.push_back({path, std::move(message)});
  }

  // The value of numeric field `field` of `j`, recording the reference in `s`; nullopt (and a
  // violation) when a reference holds something that is not a number.
  std::optional<double> number(const json& j, const std::string& field, const std::string& path,
                               Step& s) {
    if (j.is_number()) return j.get<double>();
    const auto ref = detail::parse_reference(j);
    const auto value = ref ? lookup(ref->name) : std::nullopt;
    if (!value) {  // the static checks make this unreachable for a parsed Procedure
      add(path, quote_value(j) + " refers to no parameter or enclosing loop variable");
      return std::nullopt;
    }
    if (!value->is_number()) {
      add(path, fmt::format("{} = {} is not a number", ref->text(), quote_value(*value)));
      return std::nullopt;
    }
    s.references[field] = ref->text();
    return ref->negated ? -value->get<double>() : value->get<double>();
  }

  // Reads numeric `field` of step `j` (a dotted field such as "soak.stable_s" reads `sub`)
  // into `dest` and checks `rule` on it: `rule` returns the broken rule's words, or "" if ok.
  template <typename Rule>
  bool field(const json& j, const std::string& field, const std::string& step_path, Step& s,
             double& dest, Rule rule) {
    const std::string key = field.substr(field.rfind('.') + 1);
    const std::string path = step_path + "." + field;
    const auto v = number(j.at(key), field, path, s);
    if (!v) return false;
    dest = *v;
    const std::string broken = rule(*v);
    if (!broken.empty()) {
      add(path, detail::shown_value(s, field, *v) + " " + broken);
      return false;
    }
    return true;
  }

  static std::string positive(double x) { return x > 0 ? "" : "must be greater than 0"; }
  static std::string any(double) { return ""; }

  std::string label(const json& j) const {
    return detail::fill_label(j["label"].get<std::string>(),
                              [this](const std::string& n) { return lookup(n); });
  }

  void set_temperature(const json& j, const std::string& path, Step& s) {
    s.kind = StepKind::kSetTemperature;
    field(j, "target_c", path, s, s.target_c, any);
    if (j.contains("ramp_c_per_min")) {
      double ramp = 0.0;
      if (field(j, "ramp_c_per_min", path, s, ramp, positive)) s.ramp_c_per_min = ramp;
    }
    s.wait_for_soak = j.contains("soak");
    if (s.wait_for_soak) {
      const json& soak = j["soak"];
      field(soak, "soak.tolerance_c", path, s, s.soak.tolerance_c, positive);
      const bool stable_ok = field(soak, "soak.stable_s", path, s, s.soak.stable_s, positive);
      field(soak, "soak.timeout_s", path, s, s.soak.timeout_s, [&](double t) -> std::string {
        if (t <= 0) return "must be greater than 0";
        if (stable_ok && t < s.soak.stable_s) {
          return "is shorter than soak.stable_s " +
                 detail::shown_value(s, "soak.stable_s", s.soak.stable_s);
        }
        return "";
      });
    }
    s.label = j.contains("label") ? label(j)
              : s.wait_for_soak
                  ? fmt::format("temperature {} degC", format_number(s.target_c))
                  : fmt::format("temperature ramp to {} degC", format_number(s.target_c));
  }

  void move(const json& j, const std::string& path, Step& s) {
    s.kind = StepKind::kMove;
    if (j.contains("up")) return point(j, path, s);
    const auto within_turn = [](double a) -> std::string {
      return std::abs(a) <= kMaxAbsAngleDeg ? "" : "is outside [-360, 360]";
    };
    field(j, "outer_deg", path, s, s.outer_deg, within_turn);
    field(j, "inner_deg", path, s, s.inner_deg, within_turn);
    s.label = j.contains("label")
                  ? label(j)
                  : fmt::format("move to outer {}, inner {}", format_number(s.outer_deg),
                                format_number(s.inner_deg));
  }

  // A move given as the body direction to point up; make_plan() finds the angles.
  void point(const json& j, const std::string& path, Step& s) {
    const json& up = j["up"];
    if (up.is_string() && parse_body_direction(up.get<std::string>())) {
      s.up = up.get<std::string>();
    } else if (const auto ref = detail::parse_reference(up)) {
      const auto value = lookup(ref->name);
      if (value && value->is_string() && parse_body_direction(value->get<std::string>())) {
        s.up = value->get<std::string>();
        s.references["up"] = ref->text();
      } else {
        add(path + ".up", fmt::format("{} = {} is not one of {}", ref->text(),
                                      value ? quote_value(*value) : "nothing", kBodyDirections));
      }
    }
    if (j.contains("imu")) s.imu = j["imu"].get<std::string>();
    s.label =
        j.contains("label") ? label(j) : fmt::format("point {} up", s.up.empty() ? "?" : s.up);
  }

  // The table axis of a rate or oscillate step: "outer", "inner" or a reference to one.
  void table_axis(const json& j, const std::string& path, Step& s) {
    const json& axis = j["axis"];
    if (axis.is_string() && (axis == "outer" || axis == "inner")) {
      s.axis = axis.get<std::string>();
    } else if (const auto ref = detail::parse_reference(axis)) {
      const auto value = lookup(ref->name);
      if (value && (*value == "outer" || *value == "inner")) {
        s.axis = value->get<std::string>();
        s.references["axis"] = ref->text();
      } else {
        add(path + ".axis", fmt::format("{} = {} is not \"outer\" or \"inner\"", ref->text(),
                                        value ? quote_value(*value) : "nothing"));
      }
    }
  }

  void rate(const json& j, const std::string& path, Step& s) {
    s.kind = StepKind::kRate;
    table_axis(j, path, s);
    const bool rate_ok = field(j, "rate_dps", path, s, s.rate_dps, [](double r) -> std::string {
      return r != 0 ? "" : "must not be 0 (record at rest with a capture step)";
    });
    s.settle_s = kDefaultSettleS;
    if (j.contains("settle_s")) {
      field(j, "settle_s", path, s, s.settle_s,
            [](double t) -> std::string { return t >= 0 ? "" : "must not be negative"; });
    }
    if (j.contains("revolutions")) {
      double revs = 0.0;
      const bool ok = field(j, "revolutions", path, s, revs, [](double n) -> std::string {
        return n > 0 && n == std::floor(n) ? "" : "must be a whole number greater than 0";
      });
      if (ok) s.revolutions = revs;
      if (ok && rate_ok) s.duration_s = revs * 360.0 / std::abs(s.rate_dps);
    } else {
      field(j, "duration_s", path, s, s.duration_s, positive);
    }
    s.label = j.contains("label")
                  ? label(j)
                  : fmt::format("{} rate {:+} deg/s", s.axis.empty() ? "?" : s.axis, s.rate_dps);
  }

  void oscillate(const json& j, const std::string& path, Step& s) {
    s.kind = StepKind::kOscillate;
    table_axis(j, path, s);
    field(j, "amplitude_deg", path, s, s.amplitude_deg, [](double a) -> std::string {
      if (!(a > 0)) return "must be greater than 0";
      return a <= kMaxAbsAngleDeg ? "" : "is beyond one turn (360)";
    });
    const bool f_ok = field(j, "frequency_hz", path, s, s.frequency_hz, positive);
    const auto whole = [](double n) -> std::string {
      return n > 0 && n == std::floor(n) ? "" : "must be a whole number greater than 0";
    };
    const bool n_ok = field(j, "cycles", path, s, s.cycles, whole);
    s.settle_cycles = kDefaultSettleCycles;
    if (j.contains("settle_cycles")) {
      field(j, "settle_cycles", path, s, s.settle_cycles,
            [](double n) -> std::string { return n >= 0 ? "" : "must not be negative"; });
    }
    if (f_ok && n_ok) s.duration_s = s.cycles / s.frequency_hz;
    s.label = j.contains("label")
                  ? label(j)
                  : fmt::format("{} sine {} deg at {} Hz", s.axis.empty() ? "?" : s.axis,
                                format_number(s.amplitude_deg), format_number(s.frequency_hz));
  }

  void power(const json& j, const std::string& path, Step& s) {
    s.kind = StepKind::kPower;
    s.power_on = j["power"] == "on";
    s.imu = j.value("imu", std::string());
    if (j.contains("settle_s")) {
      field(j, "settle_s", path, s, s.settle_s,
            [](double v) -> std::string { return v >= 0.0 ? "" : "must not be negative"; });
    }
    s.label = j.contains("label") ? label(j)
                                  : fmt::format("power {} {}", s.imu.empty() ? "all" : s.imu,
                                                s.power_on ? "on" : "off");
  }

  void timed(const json& j, const std::string& path, Step& s, StepKind kind) {
    s.kind = kind;
    field(j, "duration_s", path, s, s.duration_s, positive);
    s.label =
        j.contains("label") ? label(j) : fmt::format("wait {} s", format_number(s.duration_s));
  }

  void for_each(const json& j, const std::string& path) {
    json resolved;
    if (j.contains("count")) {
      // count: the loop variable runs 1..N (a power-cycle number, say).
      json count = j["count"];
      if (const auto ref = detail::parse_reference(count)) {
        const auto value = lookup(ref->name);
        if (!value) return;  // unreachable after the static checks
        count = *value;
      }
      const double n = count.is_number() ? count.get<double>() : 0.0;
      if (!(n >= 1.0 && n <= 10000.0) || n != std::floor(n)) {
        add(path + ".count", fmt::format("{} is not a whole number from 1 to 10000", count.dump()));
        return;
      }
      for (int k = 1; k <= static_cast<int>(n); ++k) resolved.push_back(k);
    }
    const json* values = j.contains("count") ? &resolved : &j["values"];
    if (const auto ref = detail::parse_reference(*values)) {
      const auto value = lookup(ref->name);
      if (!value || !value->is_array()) {  // unreachable after the static checks
        add(path + ".values", ref->text() + " is not a list");
        return;
      }
      resolved = *value;
      if (resolved.empty()) {
        add(path + ".values", ref->text() + " = [] is empty: the loop would run no steps");
        return;
      }
      values = &resolved;
    }
    const std::string var = j["var"].get<std::string>();
    for (const auto& value : *values) {
      scope_.emplace_back(var, value);
      steps(j["steps"], path + ".steps");
      scope_.pop_back();
      if (overflow_) return;
    }
  }

  void step(const json& j, const std::string& path) {
    const std::string kind = j["kind"].get<std::string>();
    if (kind == "for_each") return for_each(j, path);
    if (steps_.size() >= kMaxExpandedSteps) {
      add("steps", fmt::format("expands to more than {} steps", kMaxExpandedSteps));
      overflow_ = true;
      return;
    }
    Step s;
    s.origin_path = path;
    s.loop_values = scope_;
    if (kind == "set_temperature")
      set_temperature(j, path, s);
    else if (kind == "move")
      move(j, path, s);
    else if (kind == "rate")
      rate(j, path, s);
    else if (kind == "capture")
      timed(j, path, s, StepKind::kCapture);
    else if (kind == "power")
      power(j, path, s);
    else if (kind == "oscillate")
      oscillate(j, path, s);
    else
      timed(j, path, s, StepKind::kWait);
    steps_.push_back(std::move(s));
  }

  std::map<std::string, json> parameters_;
  std::vector<Violation>& out_;
  std::vector<std::pair<std::string, json>> scope_;
  std::vector<Step> steps_;
  std::set<std::pair<std::string, std::string>> seen_;
  bool overflow_ = false;
};

}  // namespace

std::vector<Step> expand_collecting(const Procedure& procedure, const Overrides& overrides,
                                    std::vector<Violation>& violations) {
  auto parameters = detail::resolve_parameters_collecting(procedure, overrides, violations);
  Expander expander(std::move(parameters), violations);
  expander.steps(procedure.doc.at("steps"), "steps");
  return expander.finish();
}

std::vector<Step> expand(const Procedure& procedure, const Overrides& overrides) {
  std::vector<Violation> violations;
  auto steps = expand_collecting(procedure, overrides, violations);
  if (!violations.empty()) throw ProcedureError(procedure.file_name, std::move(violations));
  return steps;
}

}  // namespace calstand::procedures

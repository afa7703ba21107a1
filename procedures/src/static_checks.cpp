#include "static_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "procedures/pointing.hpp"
#include "references.hpp"

namespace calstand::procedures::detail {
namespace {

using nlohmann::json;
using Type = ParameterSpec::Type;

std::optional<Type> type_named(const std::string& s) {
  if (s == "number") return Type::kNumber;
  if (s == "string") return Type::kString;
  if (s == "number_list") return Type::kNumberList;
  if (s == "string_list") return Type::kStringList;
  return std::nullopt;
}

// The type a default implies; nullopt (with a violation) when it implies none.
std::optional<Type> infer_type(const json& value, const std::string& path,
                               std::vector<Violation>& out) {
  if (value.is_number()) return Type::kNumber;
  if (value.is_string()) return Type::kString;
  if (value.empty()) {
    out.push_back({path, "[] is empty, so its type cannot be inferred; declare \"type\""});
    return std::nullopt;
  }
  const bool numbers =
      std::all_of(value.begin(), value.end(), [](const json& e) { return e.is_number(); });
  const bool strings =
      std::all_of(value.begin(), value.end(), [](const json& e) { return e.is_string(); });
  if (numbers) return Type::kNumberList;
  if (strings) return Type::kStringList;
  out.push_back({path, format_value(value) + " mixes numbers and strings"});
  return std::nullopt;
}

const char* const kNumericFields[][5] = {
    // kind, then its numeric fields (nullptr-terminated)
    {"set_temperature", "target_c", "ramp_c_per_min", nullptr, nullptr},
    {"move", "outer_deg", "inner_deg", nullptr, nullptr},
    {"rate", "rate_dps", "settle_s", "duration_s", nullptr},
    {"capture", "duration_s", nullptr, nullptr, nullptr},
    {"wait", "duration_s", nullptr, nullptr, nullptr},
    {"power", "settle_s", nullptr, nullptr, nullptr},
    {"oscillate", "amplitude_deg", "frequency_hz", "cycles", "settle_cycles"},
};

/// Walks the step tree with the loop variables in scope.
class StepChecker {
 public:
  StepChecker(const std::map<std::string, ParameterSpec>& specs, std::vector<Violation>& out)
      : specs_(specs), out_(out) {}

  void steps(const json& list, const std::string& path) {
    for (std::size_t i = 0; i < list.size(); ++i) {
      step(list[i], fmt::format("{}[{}]", path, i));
    }
  }

 private:
  struct LoopVar {
    std::string name;
    std::string path;  // of the for_each step
  };

  bool in_scope(const std::string& name) const {
    return specs_.count(name) > 0 || std::any_of(scope_.begin(), scope_.end(),
                                                 [&](const LoopVar& v) { return v.name == name; });
  }

  void unknown(const std::string& path, const std::string& ref_text) {
    out_.push_back({path, ref_text + " refers to no parameter or enclosing loop variable"});
  }

  // A field that holds a number or a reference to a number.
  void numeric(const json& value, const std::string& path) {
    if (value.is_number()) return;
    const auto ref = parse_reference(value);
    if (!ref) {
      out_.push_back({path, quote_value(value) + " is neither a number nor a reference ${name}"});
      return;
    }
    if (!in_scope(ref->name)) return unknown(path, ref->text());
    scalar_parameter(*ref, path, Type::kNumber);
  }

  // A reference to a parameter (not shadowed: loop variables never shadow) must have the
  // field's scalar type; loop variables are checked value by value at expansion.
  void scalar_parameter(const Reference& ref, const std::string& path, Type wanted) {
    const auto it = specs_.find(ref.name);
    if (it == specs_.end()) return;
    const Type t = it->second.type;
    if (t != wanted) {
      out_.push_back({path, fmt::format("{} is a {} parameter, not a {}", ref.text(), to_string(t),
                                        to_string(wanted))});
    }
  }

  void label(const json& step, const std::string& path) {
    if (!step.contains("label")) return;
    for (const auto& name : label_references(step["label"].get<std::string>())) {
      if (!in_scope(name)) unknown(path + ".label", "${" + name + "}");
    }
  }

  void axis(const json& value, const std::string& path) {
    if (value == "outer" || value == "inner") return;
    const auto ref = parse_reference(value);
    if (!ref || ref->negated) {
      out_.push_back(
          {path, quote_value(value) + " is not \"outer\", \"inner\" or a reference ${name}"});
      return;
    }
    if (!in_scope(ref->name)) return unknown(path, ref->text());
    scalar_parameter(*ref, path, Type::kString);
  }

  // `up` of a move: a body direction "+x" ... "-z", or a reference to a string holding one.
  void up(const json& value, const std::string& path) {
    if (value.is_string() && parse_body_direction(value.get<std::string>())) return;
    const auto ref = parse_reference(value);
    if (!ref || ref->negated) {
      out_.push_back({path, quote_value(value) +
                                " is not a body direction (\"+x\", \"-x\", \"+y\", \"-y\", "
                                "\"+z\", \"-z\") or a reference ${name}"});
      return;
    }
    if (!in_scope(ref->name)) return unknown(path, ref->text());
    scalar_parameter(*ref, path, Type::kString);
  }

  // A move gives both angles (the schema requires them without `up`), or the body direction
  // to point up (and optionally whose), not both.
  void move(const json& step, const std::string& path) {
    const bool by_up = step.contains("up");
    if (by_up) up(step["up"], path + ".up");
    if (by_up && (step.contains("outer_deg") || step.contains("inner_deg"))) {
      out_.push_back({path, "has both up and table angles; give outer_deg and inner_deg, or up"});
    }
    if (step.contains("imu") && !by_up) {
      out_.push_back({path + ".imu", "names the IMU whose body axis up points; it needs up"});
    }
  }

  void for_each(const json& step, const std::string& path) {
    const std::string var = step["var"].get<std::string>();
    if (specs_.count(var) > 0) {
      out_.push_back({path + ".var", fmt::format("\"{}\" shadows the parameter {}", var, var)});
    }
    for (const auto& outer : scope_) {
      if (outer.name == var) {
        out_.push_back({path + ".var", fmt::format("\"{}\" shadows the variable of the enclosing "
                                                   "loop {}",
                                                   var, outer.path)});
      }
    }
    if (step.contains("count")) {
      // A count given by reference must name a number parameter; its value (a whole number
      // from 1) is checked where it is expanded, as the parameter may be overridden.
      if (const auto ref = parse_reference(step["count"]); step["count"].is_string()) {
        if (!ref || ref->negated) {
          out_.push_back({path + ".count", quote_value(step["count"]) +
                                               " is neither a number nor a reference ${name}"});
        } else if (specs_.count(ref->name) == 0) {
          out_.push_back({path + ".count", ref->text() + " refers to no parameter"});
        } else if (specs_.at(ref->name).type != Type::kNumber) {
          out_.push_back(
              {path + ".count", fmt::format("{} is a {} parameter, not a number", ref->text(),
                                            to_string(specs_.at(ref->name).type))});
        }
      }
    }
    const json& values = step.contains("values") ? step["values"] : json::array({1});
    if (values.is_array()) {
      if (values.empty())
        out_.push_back({path + ".values", "[] is empty: the loop would run no steps"});
    } else {
      const auto ref = parse_reference(values);
      if (!ref || ref->negated) {
        out_.push_back({path + ".values",
                        quote_value(values) +
                            " is neither a list nor a reference ${name} to a list parameter"});
      } else if (specs_.count(ref->name) == 0) {
        out_.push_back({path + ".values", ref->text() + " refers to no list parameter"});
      } else {
        const Type t = specs_.at(ref->name).type;
        if (t != Type::kNumberList && t != Type::kStringList) {
          out_.push_back({path + ".values", fmt::format("{} is a {} parameter, not a list",
                                                        ref->text(), to_string(t))});
        }
      }
    }
    if (step["steps"].empty()) {
      out_.push_back({path + ".steps", "[] is empty: the loop would run no steps"});
    }
    scope_.push_back({var, path});
    steps(step["steps"], path + ".steps");
    scope_.pop_back();
  }

  void step(const json& step, const std::string& path) {
    const std::string kind = step["kind"].get<std::string>();
    label(step, path);
    if (kind == "for_each") return for_each(step, path);
    for (const auto& row : kNumericFields) {
      if (kind != row[0]) continue;
      for (int f = 1; f < 5 && row[f] != nullptr; ++f) {
        if (step.contains(row[f])) numeric(step[row[f]], path + "." + row[f]);
      }
    }
    if (kind == "set_temperature" && step.contains("soak")) {
      for (const char* f : {"tolerance_c", "stable_s", "timeout_s"}) {
        numeric(step["soak"][f], path + ".soak." + f);
      }
    }
    if (kind == "move") move(step, path);
    if (kind == "oscillate") axis(step["axis"], path + ".axis");
    if (kind == "rate") {
      axis(step["axis"], path + ".axis");
      if (step.contains("revolutions")) numeric(step["revolutions"], path + ".revolutions");
      const bool d = step.contains("duration_s"), r = step.contains("revolutions");
      if (d && r) out_.push_back({path, "has both duration_s and revolutions; give exactly one"});
      if (!d && !r)
        out_.push_back({path, "has neither duration_s nor revolutions; give exactly one"});
    }
  }

  const std::map<std::string, ParameterSpec>& specs_;
  std::vector<Violation>& out_;
  std::vector<LoopVar> scope_;
};

}  // namespace

std::vector<Violation> check_parameter_value(const ParameterSpec& spec, const json& value,
                                             const std::string& path) {
  std::vector<Violation> out;
  const bool list = spec.type == Type::kNumberList || spec.type == Type::kStringList;
  const bool numbers = spec.type == Type::kNumber || spec.type == Type::kNumberList;
  const auto type_ok = [&](const json& v) { return numbers ? v.is_number() : v.is_string(); };
  const auto range = [&](const json& v, const std::string& p) {
    if (!v.is_number()) return;
    const double x = v.get<double>();
    if (spec.min && x < *spec.min) {
      out.push_back({p, fmt::format("{} is below the minimum {}", format_value(v),
                                    format_number(*spec.min))});
    }
    if (spec.max && x > *spec.max) {
      out.push_back({p, fmt::format("{} is above the maximum {}", format_value(v),
                                    format_number(*spec.max))});
    }
  };
  if (list != value.is_array() || (!list && !type_ok(value))) {
    out.push_back({path, fmt::format("{} is not a {} (parameter {} is a {})", quote_value(value),
                                     list ? "list" : (numbers ? "number" : "string"), spec.name,
                                     to_string(spec.type))});
    return out;
  }
  if (!list) {
    range(value, path);
    return out;
  }
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string p = fmt::format("{}[{}]", path, i);
    if (!type_ok(value[i])) {
      out.push_back(
          {p, fmt::format("{} is not a {} (parameter {} is a {})", quote_value(value[i]),
                          numbers ? "number" : "string", spec.name, to_string(spec.type))});
    } else {
      range(value[i], p);
    }
  }
  return out;
}

std::map<std::string, ParameterSpec> read_parameter_specs(const json& doc,
                                                          std::vector<Violation>& out) {
  std::map<std::string, ParameterSpec> specs;
  if (!doc.contains("parameters")) return specs;
  for (const auto& [name, decl] : doc["parameters"].items()) {
    const std::string path = "parameters." + name;
    ParameterSpec spec;
    spec.name = name;
    spec.default_value = decl["default"];
    spec.description = decl["description"].get<std::string>();
    if (decl.contains("min")) spec.min = decl["min"].get<double>();
    if (decl.contains("max")) spec.max = decl["max"].get<double>();
    std::optional<Type> type;
    if (decl.contains("type")) {
      type = type_named(decl["type"].get<std::string>());  // the schema allows only known names
    } else {
      type = infer_type(spec.default_value, path + ".default", out);
    }
    if (!type) continue;
    spec.type = *type;
    if ((spec.min || spec.max) && (spec.type == Type::kString || spec.type == Type::kStringList)) {
      out.push_back(
          {path + (spec.min ? ".min" : ".max"),
           fmt::format("applies only to numbers, and {} is a {}", name, to_string(spec.type))});
    }
    ParameterSpec checked = spec;
    if (spec.min && spec.max && *spec.min > *spec.max) {
      out.push_back({path + ".min", fmt::format("{} is above max {}", format_number(*spec.min),
                                                format_number(*spec.max))});
      checked.min.reset();  // no default can satisfy both: one message is enough
      checked.max.reset();
    }
    auto bad = check_parameter_value(checked, spec.default_value, path + ".default");
    out.insert(out.end(), bad.begin(), bad.end());
    specs.emplace(name, std::move(spec));
  }
  return specs;
}

void check_steps(const json& doc, const std::map<std::string, ParameterSpec>& specs,
                 std::vector<Violation>& out) {
  if (doc["steps"].empty()) {
    out.push_back({"steps", "[] is empty: the procedure has no steps"});
    return;
  }
  StepChecker(specs, out).steps(doc["steps"], "steps");
}

}  // namespace calstand::procedures::detail

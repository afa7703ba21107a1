// The simulator's side of a command set (command_set_server.hpp): command templates made into
// patterns, the simulated device's values put into the steps' reply formats.
#include "drivers/command_set_server.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>

namespace calstand::drivers::line {
namespace {

std::string regex_escape(std::string_view text) {
  static const std::string kSpecial = R"(\^$.|?*+()[]{})";
  std::string out;
  for (const char c : text) {
    if (kSpecial.find(c) != std::string::npos) out.push_back('\\');
    out.push_back(c);
  }
  return out;
}

/// A template's pattern: literal text escaped, each replacement field `{name[:spec]}` a lazy
/// capture; `names` gets the fields' names in order. `{{` and `}}` are fmt's literal braces.
std::string template_pattern(std::string_view templ, std::vector<std::string>& names) {
  std::string out;
  std::string literal;
  for (std::size_t i = 0; i < templ.size(); ++i) {
    const char c = templ[i];
    if ((c == '{' || c == '}') && i + 1 < templ.size() && templ[i + 1] == c) {
      literal.push_back(c);
      ++i;
      continue;
    }
    if (c == '{') {
      const std::size_t end = templ.find('}', i);
      const std::string_view field = templ.substr(i + 1, end - i - 1);
      names.emplace_back(field.substr(0, field.find(':')));
      out += regex_escape(literal);
      literal.clear();
      out += "(.*?)";
      i = end;
      continue;
    }
    literal.push_back(c);
  }
  return out + regex_escape(literal);
}

std::size_t literal_length(std::string_view templ) {
  std::size_t n = 0;
  bool in_field = false;
  for (const char c : templ) {
    if (c == '{') in_field = true;
    if (!in_field) ++n;
    if (c == '}') in_field = false;
  }
  return n;
}

std::optional<double> number_of(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '+')) text.remove_prefix(1);
  while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
  double v = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size() ||
      !std::isfinite(v)) {
    return std::nullopt;
  }
  return v;
}

std::string mode_name(acutrol::WireMode mode) {
  switch (mode) {
    case acutrol::WireMode::kRest:
      return "rest";
    case acutrol::WireMode::kPosition:
      return "position";
    case acutrol::WireMode::kRate:
      return "rate";
    case acutrol::WireMode::kSine:
      return "sine";
    case acutrol::WireMode::kFault:
      return "fault";
  }
  return "fault";
}

FieldValue number_value(double v) {
  FieldValue f;
  f.number = v;
  return f;
}
FieldValue truth_value(bool v) {
  FieldValue f;
  f.truth = v;
  return f;
}
FieldValue text_value(std::string v) {
  FieldValue f;
  f.text = std::move(v);
  return f;
}

/// The reply format's arguments from the device's values, in the step's encoding: a map
/// field's device text, a bit field's 0/1 and its group's word (`word<group>`), a number
/// divided by its scale.
Arguments reply_arguments(const Step& step, const Fields& values) {
  Arguments a;
  for (const auto& [name, v] : values) {
    if (v.number) a.numbers[name] = *v.number;
    if (v.truth) a.numbers[name] = *v.truth ? 1.0 : 0.0;
    if (v.text) a.texts[name] = *v.text;
  }
  std::map<int, unsigned long long> words;
  for (const auto& [name, spec] : step.fields) {
    const auto it = values.find(name);
    if (it == values.end()) continue;
    const FieldValue& v = it->second;
    switch (spec.kind) {
      case FieldSpec::Kind::kNumber:
        if (v.number && spec.scale != 0.0) a.numbers[name] = *v.number / spec.scale;
        a.texts.erase(name);
        break;
      case FieldSpec::Kind::kBit: {
        const bool set = v.truth.value_or(v.number.value_or(0.0) != 0.0) != spec.invert;
        a.numbers[name] = set ? 1.0 : 0.0;
        a.texts.erase(name);
        if (set) words[spec.group] |= 1ull << spec.bit;
        words.try_emplace(spec.group, 0ull);
        break;
      }
      case FieldSpec::Kind::kMap: {
        std::string value = v.text.value_or("");
        if (v.truth) value = *v.truth ? "1" : "0";
        for (const auto& [device_text, meaning] : spec.map) {
          if (meaning == value) {
            a.texts[name] = device_text;
            a.numbers.erase(name);
            break;
          }
        }
        break;
      }
      case FieldSpec::Kind::kText:
      case FieldSpec::Kind::kMatch:
        break;
    }
  }
  for (const auto& [group, word] : words) {
    a.numbers[fmt::format("word{}", group)] = static_cast<double>(word);
  }
  return a;
}

}  // namespace

struct CommandSetHandler::Pattern {
  std::regex pattern;
  std::vector<std::string> names;
  std::string operation;
  std::size_t step_index = 0;
  std::size_t literal = 0;
};

CommandSetHandler::CommandSetHandler(CommandSet set, TableServerBackend& table)
    : set_(std::move(set)), table_(&table) {
  compile();
}

CommandSetHandler::CommandSetHandler(CommandSet set, ChamberServerBackend& chamber)
    : set_(std::move(set)), chamber_(&chamber) {
  compile();
}

CommandSetHandler::~CommandSetHandler() = default;

void CommandSetHandler::compile() {
  std::vector<std::string> prefix_names;
  const std::string prefix = template_pattern(set_.line.prefix, prefix_names);
  for (const auto& [name, op] : set_.operations) {
    for (std::size_t i = 0; i < op.steps.size(); ++i) {
      Pattern p;
      p.names = prefix_names;
      p.pattern = std::regex("^" + prefix + template_pattern(op.steps[i].command, p.names) + "$");
      p.operation = name;
      p.step_index = i;
      p.literal = literal_length(op.steps[i].command);
      patterns_.push_back(std::move(p));
    }
  }
  // The most specific command first, so that "TEMP?" is never taken for "TEMP{x}".
  std::stable_sort(patterns_.begin(), patterns_.end(),
                   [](const Pattern& a, const Pattern& b) { return a.literal > b.literal; });
}

std::string CommandSetHandler::refuse(const std::string& why) const {
  if (set_.error_format.empty()) return {};
  Arguments a;
  a.texts["text"] = why;
  return render(set_.error_format, a, set_.name + ": error_format");
}

std::optional<std::string> CommandSetHandler::handle(std::string_view line) {
  while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.remove_suffix(1);
  if (line.empty()) return std::nullopt;
  std::lock_guard lock(mutex_);
  for (const Pattern& p : patterns_) {
    std::match_results<std::string_view::const_iterator> m;
    if (!std::regex_match(line.begin(), line.end(), m, p.pattern)) continue;
    Arguments args;
    for (std::size_t i = 0; i < p.names.size(); ++i) {
      const std::string text = m[i + 1].str();
      if (p.names[i] == "axis" || p.names[i] == "address") {
        args.texts[p.names[i]] = text;
      } else if (const auto v = number_of(text)) {
        args.numbers[p.names[i]] = *v;
      } else {
        return refuse(fmt::format("{}: \"{}\" is not a number", p.names[i], text));
      }
    }
    return act(p.operation, p.step_index, args);
  }
  return refuse(fmt::format("unknown command \"{}\"", line));
}

std::optional<std::string> CommandSetHandler::act(const std::string& operation,
                                                  std::size_t step_index, const Arguments& args) {
  const Operation& op = *set_.find(operation);
  Arguments& pending = pending_[operation];
  std::size_t& expected = next_step_[operation];
  if (step_index == 0) {
    pending = Arguments{};
  } else if (step_index != expected) {
    // As a controller refuses a demand for a mode not selected: the steps come in order.
    expected = 0;
    return refuse(fmt::format("\"{}\" first", op.steps[expected].command));
  }
  expected = step_index + 1 == op.steps.size() ? 0 : step_index + 1;
  for (const auto& [k, v] : args.numbers) pending.numbers[k] = v;
  for (const auto& [k, v] : args.texts) pending.texts[k] = v;
  const Step& step = op.steps[step_index];
  Fields values;
  // The device acts on the operation's last step, with what every step carried.
  if (step_index + 1 == op.steps.size()) {
    std::string refusal;
    values = table_ != nullptr ? table_fields(operation, pending, refusal)
                               : chamber_fields(operation, pending, refusal);
    if (!refusal.empty()) return refuse(refusal);
  }
  if (!step.reply) return std::nullopt;
  if (!step.reply_format) return refuse(operation + " is not served by this simulator");
  for (const auto& [k, v] : pending.numbers) values.try_emplace(k, number_value(v));
  return render(*step.reply_format, reply_arguments(step, values),
                set_.name + ": operations." + operation + ".reply_format");
}

Fields CommandSetHandler::table_fields(const std::string& operation, const Arguments& args,
                                       std::string& refusal) {
  Fields out;
  int axis = 0;
  if (const auto it = args.texts.find("axis"); it != args.texts.end()) {
    if (it->second == set_.outer_axis) axis = acutrol::kOuterAxis;
    if (it->second == set_.inner_axis) axis = acutrol::kInnerAxis;
    if (axis == 0) {
      refusal = fmt::format("axis \"{}\" is neither {} nor {}", it->second, set_.outer_axis,
                            set_.inner_axis);
      return out;
    }
  }
  const auto number = [&](const char* name) {
    const auto it = args.numbers.find(name);
    return it == args.numbers.end() ? std::nan("") : it->second;
  };
  const auto refused = [&](const Refusal& r) {
    if (r) refusal = r->text;
    return out;
  };
  if (operation != "identify" && axis == 0) {
    refusal = "no axis";
    return out;
  }
  if (operation == "identify") {
    out["identity"] = text_value(table_->identity());
  } else if (operation == "set_limits") {
    return refused(table_->set_limits(axis, number("max_rate_dps"), number("max_accel_dps2")));
  } else if (operation == "position") {
    if (auto r = table_->select_mode(axis, acutrol::WireMode::kPosition)) return refused(r);
    return refused(table_->demand_position(axis, number("angle_deg")));
  } else if (operation == "rate") {
    if (auto r = table_->select_mode(axis, acutrol::WireMode::kRate)) return refused(r);
    return refused(table_->demand_rate(axis, number("rate_dps")));
  } else if (operation == "sine") {
    if (auto r = table_->select_mode(axis, acutrol::WireMode::kSine)) return refused(r);
    return refused(table_->demand_sine(axis, number("amplitude_deg"), number("frequency_hz")));
  } else if (operation == "stop") {
    table_->stop(axis);
  } else if (operation == "read_position" || operation == "read_rate" ||
             operation == "read_status") {
    const auto report = table_->report(axis);
    out["angle_deg"] = number_value(report.angle_deg);
    out["rate_dps"] = number_value(report.rate_dps);
    out["mode"] = text_value(mode_name(report.status.mode));
    out["in_position"] = truth_value(report.status.settled);
    out["fault"] = truth_value(report.status.mode == acutrol::WireMode::kFault);
    out["fault_text"] = text_value(report.status.fault_text);
    out["open"] = truth_value(report.status.interlock_open);
  } else if (operation == "read_interlock") {
    const auto interlock = table_->interlock(axis);
    out["open"] = truth_value(interlock.open);
    out["why"] = text_value(interlock.why);
  } else if (operation == "close_interlock") {
    return refused(table_->close_interlock(axis));
  }
  return out;
}

Fields CommandSetHandler::chamber_fields(const std::string& operation, const Arguments& args,
                                         std::string& refusal) {
  Fields out;
  const auto number = [&](const char* name) {
    const auto it = args.numbers.find(name);
    return it == args.numbers.end() ? std::nan("") : it->second;
  };
  const auto result = [&](const Result& r) {
    if (!r) refusal = r.message;
    return out;
  };
  if (operation == "identify") {
    out["identity"] = text_value("CALSTAND,CHAMBER-SIM," + set_.name);
  } else if (operation == "set_setpoint") {
    return result(chamber_->set_setpoint(number("setpoint_c")));
  } else if (operation == "set_ramp") {
    // A set whose ramp command carries the target too (SimServ's gradients and setpoint).
    if (auto r = chamber_->set_ramp(number("ramp_c_per_min")); !r) return result(r);
    if (args.numbers.count("setpoint_c") > 0) {
      return result(chamber_->set_setpoint(number("setpoint_c")));
    }
  } else if (operation == "start") {
    return result(chamber_->set_mode(ChamberServerBackend::Mode::kControl));
  } else if (operation == "standby") {
    return result(chamber_->set_mode(ChamberServerBackend::Mode::kStandby));
  } else if (operation == "read_alarms") {
    const auto s = chamber_->state();
    out["alarm"] = truth_value(s.fault);
    out["alarm_count"] = number_value(s.fault ? 1.0 : 0.0);
    out["alarm_text"] = text_value(s.fault_text);
  } else {
    // read_air, read_setpoint, read_mode: the whole state, each step takes its fields.
    const auto s = chamber_->state();
    out["air_c"] = number_value(s.air_temperature_c);
    out["setpoint_c"] = number_value(s.setpoint_c);
    out["mode"] = text_value(s.mode == core::ChamberMode::kActive    ? "active"
                             : s.mode == core::ChamberMode::kStandby ? "standby"
                                                                     : "fault");
    out["active"] = truth_value(s.mode == core::ChamberMode::kActive);
    out["alarm"] = truth_value(s.fault);
  }
  return out;
}

std::unique_ptr<AcutrolServer> make_command_set_server(std::shared_ptr<CommandSetHandler> handler,
                                                       AcutrolServerOptions options) {
  options.cr_ends_line = true;
  options.reply_terminator = handler->command_set().line.terminator;
  return std::make_unique<AcutrolServer>(
      [handler](std::string_view line, bool overlong) -> std::optional<std::string> {
        if (overlong) return std::nullopt;
        return handler->handle(line);
      },
      std::move(options));
}

}  // namespace calstand::drivers::line

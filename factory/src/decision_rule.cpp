#include "factory/decision_rule.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace calstand::analysis {
namespace {

std::string number(double v) { return fmt::format("{:.6g}", v); }

std::string with_unit(double v, const std::string& unit) {
  return unit.empty() ? number(v) : number(v) + " " + unit;
}

// "2 sigma" for the guard band in words.
std::string band(double k) { return number(k) + " sigma"; }

}  // namespace

std::string_view to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::kPass:
      return "pass";
    case Verdict::kIndeterminate:
      return "indeterminate";
    case Verdict::kFail:
      return "fail";
  }
  return "fail";
}

std::string limit_kind(const Bounds& b) {
  std::string kind;
  if (b.max_abs) kind = "max_abs";
  const char* side = b.min && b.max ? "min_max" : b.min ? "min" : b.max ? "max" : nullptr;
  if (side) kind += (kind.empty() ? "" : "+") + std::string(side);
  return kind;
}

nlohmann::json limit_json(const Bounds& b) {
  const int set = (b.max_abs ? 1 : 0) + (b.min ? 1 : 0) + (b.max ? 1 : 0);
  // One bound is the number a reader expects next to a value; a zone is its two ends.
  if (set == 1) return b.max_abs ? *b.max_abs : b.min ? *b.min : *b.max;
  if (set == 2 && b.min && b.max) return nlohmann::json::array({*b.min, *b.max});
  if (set == 0) return nullptr;
  nlohmann::json j = nlohmann::json::object();
  if (b.max_abs) j["max_abs"] = *b.max_abs;
  if (b.min) j["min"] = *b.min;
  if (b.max) j["max"] = *b.max;
  return j;
}

std::string describe(const Bounds& b, const std::string& unit) {
  std::vector<std::string> parts;
  if (b.max_abs) parts.push_back("|v| <= " + with_unit(*b.max_abs, unit));
  if (b.min && b.max) {
    parts.push_back(number(*b.min) + " <= v <= " + with_unit(*b.max, unit));
  } else if (b.min) {
    parts.push_back("v >= " + with_unit(*b.min, unit));
  } else if (b.max) {
    parts.push_back("v <= " + with_unit(*b.max, unit));
  }
  if (parts.empty()) return "no limit";
  std::string text = parts.front();
  for (std::size_t i = 1; i < parts.size(); ++i) text += " and " + parts[i];
  return text;
}

Judgement judge(double value, double sigma, const Bounds& b, double k) {
  if (!std::isfinite(value)) return {Verdict::kFail, "the value is not a number"};
  if (!std::isfinite(sigma) || sigma < 0.0) return {Verdict::kFail, "the sigma is not a number"};
  const double w = k * sigma;
  const double lo = value - w;
  const double hi = value + w;
  std::vector<Verdict> sides;
  std::vector<std::string> reasons;
  // The ends of the interval in words: "v + 2 sigma", or plain "v" without a guard band.
  const std::string plus = w > 0.0 ? " + " + band(k) : "";
  const std::string minus = w > 0.0 ? " - " + band(k) : "";
  // Each limit is judged on its own; the zone is their intersection, so the interval is wholly
  // outside it as soon as it is wholly beyond one limit, and inside only when inside all.
  if (b.max_abs) {
    const double a = std::abs(value);
    const double limit = *b.max_abs;
    if (a + w <= limit) {
      sides.push_back(Verdict::kPass);
      reasons.push_back(fmt::format("|v|{} = {} <= {}", plus, number(a + w), number(limit)));
    } else if (a - w > limit) {
      sides.push_back(Verdict::kFail);
      reasons.push_back(fmt::format("|v|{} = {} > {}", minus, number(a - w), number(limit)));
    } else {
      sides.push_back(Verdict::kIndeterminate);
      reasons.push_back(fmt::format("|v|{} = {} <= {} < |v|{} = {}", minus, number(a - w),
                                    number(limit), plus, number(a + w)));
    }
  }
  if (b.min) {
    if (lo >= *b.min) {
      sides.push_back(Verdict::kPass);
      reasons.push_back(fmt::format("v{} = {} >= {}", minus, number(lo), number(*b.min)));
    } else if (hi < *b.min) {
      sides.push_back(Verdict::kFail);
      reasons.push_back(fmt::format("v{} = {} < {}", plus, number(hi), number(*b.min)));
    } else {
      sides.push_back(Verdict::kIndeterminate);
      reasons.push_back(fmt::format("v{} = {} < {} <= v{} = {}", minus, number(lo), number(*b.min),
                                    plus, number(hi)));
    }
  }
  if (b.max) {
    if (hi <= *b.max) {
      sides.push_back(Verdict::kPass);
      reasons.push_back(fmt::format("v{} = {} <= {}", plus, number(hi), number(*b.max)));
    } else if (lo > *b.max) {
      sides.push_back(Verdict::kFail);
      reasons.push_back(fmt::format("v{} = {} > {}", minus, number(lo), number(*b.max)));
    } else {
      sides.push_back(Verdict::kIndeterminate);
      reasons.push_back(fmt::format("v{} = {} <= {} < v{} = {}", minus, number(lo), number(*b.max),
                                    plus, number(hi)));
    }
  }
  if (sides.empty()) return {Verdict::kFail, "no limit to judge against"};
  const Verdict verdict = combine(sides);
  // The reason names the limits that decided: the failing ones for a fail, the straddled ones
  // for an indeterminate, all for a pass.
  std::string reason;
  for (std::size_t i = 0; i < sides.size(); ++i) {
    if (verdict != Verdict::kPass && sides[i] != verdict) continue;
    reason += (reason.empty() ? "" : "; ") + reasons[i];
  }
  return {verdict, reason};
}

Verdict combine(const std::vector<Verdict>& verdicts) {
  if (verdicts.empty()) return Verdict::kIndeterminate;
  if (std::find(verdicts.begin(), verdicts.end(), Verdict::kFail) != verdicts.end()) {
    return Verdict::kFail;
  }
  if (std::find(verdicts.begin(), verdicts.end(), Verdict::kIndeterminate) != verdicts.end()) {
    return Verdict::kIndeterminate;
  }
  return Verdict::kPass;
}

std::string decision_rule_text(double k) {
  return fmt::format(
      "simple acceptance with guard band w = k sigma, k = {} (ILAC G8:2019, ISO 14253-1): a "
      "check passes when value +- w lies inside the limit (limits included), fails when it lies "
      "wholly outside, and is indeterminate otherwise; a check without an uncertainty in the "
      "record has sigma 0; a unit fails when any check fails, else is indeterminate when any "
      "check is, else passes",
      number(k));
}

}  // namespace calstand::analysis

#pragma once
// The decision rule of acceptance: simple acceptance with a guard band (ILAC G8:2019, ISO
// 14253-1). A measured value v with standard uncertainty sigma stands for the interval
// [v - w, v + w], w = k sigma. A check passes when that interval lies inside the specification
// zone, fails when it lies wholly outside, and is indeterminate when it straddles a limit.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::analysis {

/// The outcome of one check or of a whole unit.
enum class Verdict { kPass, kIndeterminate, kFail };

/// "pass", "indeterminate" or "fail" (the strings the acceptances table stores).
std::string_view to_string(Verdict verdict);

/// A specification zone: any of |v| <= max_abs, v >= min, v <= max (limits belong to the
/// zone). At least one is set for a zone that limits anything.
struct Bounds {
  std::optional<double> max_abs;
  std::optional<double> min;
  std::optional<double> max;
};

/// The zone's kind: "max_abs", "min", "max" or "min_max" (or "max_abs+min_max" and the like
/// for a zone of several kinds, which a specification does not write).
std::string limit_kind(const Bounds& bounds);

/// The zone's limit as a number (max_abs, min or max: the one bound), [min, max] for a
/// two-sided zone, {"max_abs", "min", "max"} for any other combination; null for none.
nlohmann::json limit_json(const Bounds& bounds);

/// The zone in words with its unit, e.g. "|v| <= 0.005 deg/s", "0.1 <= v <= 2", "v <= 2".
std::string describe(const Bounds& bounds, const std::string& unit);

/// A judged value and why it got its verdict.
struct Judgement {
  Verdict verdict = Verdict::kFail;
  std::string reason;  ///< e.g. "|v| + 2 sigma = 0.0031 <= 0.005"
};

/// Judges `value` with standard uncertainty `sigma` (>= 0; 0 = no guard band) against
/// `bounds` with coverage factor `k`: pass when [v - k sigma, v + k sigma] lies inside the
/// zone, fail when it lies wholly outside (below min or above max, or |v| - k sigma > max_abs),
/// else indeterminate. A value or sigma that is not a finite number fails.
Judgement judge(double value, double sigma, const Bounds& bounds, double k);

/// The verdict of a unit from its checks: fail if any fails, else indeterminate if any is,
/// else pass (a unit without checks passes nothing and is indeterminate).
Verdict combine(const std::vector<Verdict>& verdicts);

/// The rule in one paragraph for the output (text and the JSON's "decision_rule").
std::string decision_rule_text(double k);

}  // namespace calstand::analysis

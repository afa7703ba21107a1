#pragma once

#include <cstddef>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/json_schema.hpp"

/// The procedure language (schemas/procedure.schema.json): parse and check a procedure, apply
/// `--set` overrides, expand loops into a flat list of steps. Planning against a station lives in
/// plan.hpp, the shipped procedures in library.hpp.
namespace calstand::procedures {

/// One broken rule: `path` is the JSON path of the field in the procedure file where the rule
/// is broken (e.g. `steps[3].rate_dps`; `--set NAME` for a command-line override), `message`
/// is `VALUE RULE` (e.g. `220 exceeds the outer axis limit 200`).
using Violation = core::SchemaViolation;

/// A procedure that breaks its schema or a rule. what() lists every violation, one per line, as
/// `FILE: PATH: MESSAGE`; where() is the file name. Schema violations come alone (the rules
/// after the schema need a well-formed document); otherwise every rule broken is listed.
class ProcedureError : public core::InputError {
 public:
  ProcedureError(const std::string& file_name, std::vector<Violation> violations);
  const std::vector<Violation>& violations() const { return violations_; }

 private:
  std::vector<Violation> violations_;
};

enum class StepKind { kSetTemperature, kMove, kRate, kCapture, kWait, kPower, kOscillate };

/// "set_temperature", "move", "rate", "capture", "wait", "power", "oscillate" (the `kind` of the
/// file).
std::string_view to_string(StepKind kind);

/// The chamber is soaked once its temperature stays within tolerance_c of the target for
/// stable_s; the step fails when that has not happened timeout_s after the step began.
struct SoakCriterion {
  double tolerance_c = 0.0;  ///< [degC], > 0
  double stable_s = 0.0;     ///< [s], > 0
  double timeout_s = 0.0;    ///< [s], >= stable_s
};

/// One step of an expanded procedure, every field resolved to a number. Only the fields of its
/// kind are meaningful; the others keep their defaults.
struct Step {
  std::size_t index = 0;  ///< position in the expanded list, from 0
  StepKind kind = StepKind::kWait;
  std::string label;        ///< for people: the file's label (with ${...} filled in) or made up
  std::string origin_path;  ///< JSON path of the step in the file, e.g. `steps[2].steps[1]`
  /// Values of the enclosing loop variables, outermost first, e.g. {"temperature", -40}.
  std::vector<std::pair<std::string, nlohmann::json>> loop_values;
  /// Fields given by reference: field name as in the file (e.g. "rate_dps", "soak.stable_s")
  /// to the reference written there (e.g. "${rate}"), so that messages can quote it.
  std::map<std::string, std::string> references;

  // kSetTemperature
  double target_c = 0.0;                 ///< chamber setpoint [degC]
  std::optional<double> ramp_c_per_min;  ///< [degC/min]; absent: the chamber's limit
  /// true: the step ends once soaked (see `soak`); false: the step only commands setpoint and
  /// ramp and ends at once, the chamber keeps ramping through the following steps (a capture
  /// then records a temperature ramp, with no temperature band to hold).
  bool wait_for_soak = false;
  SoakCriterion soak;  ///< meaningful when wait_for_soak

  // kMove: absolute angles, reached the shortest way round [deg]. A move given by pointing
  // (`up`) has them filled in by make_plan() for the station's table and the IMU's mount;
  // expand() leaves them 0.
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  /// kMove by pointing: the body direction to point up, "+x" ... "-z"; empty when the file
  /// gives the angles.
  std::string up;
  /// kMove by pointing: the IMU whose body axes `up` names; empty for the station's first.
  std::string imu;

  // kRate: a capture at constant rate.
  std::string axis;       ///< "outer" or "inner"
  double rate_dps = 0.0;  ///< signed, right-handed about the axis [deg/s], never 0
  double settle_s = 0.0;  ///< at constant rate before recording starts [s]
  /// Whether the axis is brought to rest at the end of this step: true unless the next step is
  /// a rate step on the same axis, which then ramps straight from this rate to its own.
  bool rest_after = true;

  // kPower: the supply of `imu` (every supplied IMU when empty) on or off, then settle_s.
  bool power_on = false;

  // kOscillate: `axis` follows angle = start + amplitude_deg sin(2 pi frequency_hz t) for
  // settle_cycles (not recorded: the servo and the IMU's output filter settle), then for cycles
  // while the IMUs and the encoder are recorded; the axis then comes back to rest at the start.
  double amplitude_deg = 0.0;  ///< > 0 [deg]
  double frequency_hz = 0.0;   ///< > 0 [Hz]
  double cycles = 0.0;         ///< recorded periods, a whole number > 0
  double settle_cycles = 0.0;  ///< periods before recording, >= 0 (default 2)
  /// Peak rate 2 pi f A [deg/s] and peak acceleration (2 pi f)^2 A [deg/s^2] of the oscillation.
  double peak_rate_dps() const;
  double peak_accel_dps2() const;

  /// kCapture, kWait, kRate, kOscillate: recording (or waiting) time [s]; for a rate step given
  /// in revolutions, revolutions * 360 / |rate_dps|; for an oscillation cycles / frequency_hz.
  double duration_s = 0.0;
  std::optional<double> revolutions;  ///< kRate given in whole revolutions

  /// True for the kinds that record IMU data (capture, rate and oscillate).
  bool records() const {
    return kind == StepKind::kCapture || kind == StepKind::kRate || kind == StepKind::kOscillate;
  }
  /// The commanded values as JSON: index, kind, label, origin, loop values and the fields of
  /// the kind, in the file's names and units.
  nlohmann::json to_json() const;
};

/// A declared parameter. `type` is declared or inferred from the default.
struct ParameterSpec {
  enum class Type { kNumber, kString, kNumberList, kStringList };
  std::string name;
  Type type = Type::kNumber;
  nlohmann::json default_value;
  std::string description;
  std::optional<double> min;  ///< numbers and number_list elements
  std::optional<double> max;
};

/// "number", "string", "number_list", "string_list".
std::string_view to_string(ParameterSpec::Type type);

/// A parsed procedure that passed its schema and every rule that does not depend on parameter
/// values (reference form and scope, loop variable names, parameter declarations).
struct Procedure {
  std::string name;  ///< the document's `name`
  std::string description;
  std::string file_name;    ///< where it came from: a path, or `library/NAME.json`
  std::string source_text;  ///< the exact text read (stored with a run)
  nlohmann::json doc;
  /// Default value of each parameter, by name.
  std::map<std::string, nlohmann::json> parameters;
  std::map<std::string, ParameterSpec> parameter_specs;
};

/// Parameter values from the command line, by name (JSON values).
using Overrides = std::map<std::string, nlohmann::json>;

/// Parses `--set` arguments `NAME=VALUE`. VALUE is JSON (`30`, `[-40,25,85]`, `"outer"`); text
/// that is not JSON is taken as a string (`axis=outer`). Throws core::InputError naming the
/// argument when `=` or the name is missing or a name is given twice. Names are checked
/// against a procedure by resolve_parameters().
Overrides parse_overrides(const std::vector<std::string>& set_args);

/// Parses procedure text read from `file_name`. Throws core::InputError on a JSON syntax error
/// (FILE:LINE:COLUMN), ProcedureError listing every schema violation, or ProcedureError listing
/// every rule broken that needs no parameter values.
Procedure parse_procedure(std::string_view text, const std::string& file_name);

/// A library procedure by name (library.hpp), else the procedure file at `name_or_path`.
/// Throws core::InputError when neither exists or the file cannot be read; parse errors as
/// parse_procedure().
Procedure load_procedure(const std::string& name_or_path);

/// Defaults with `overrides` applied. Throws ProcedureError (paths `--set NAME`) on an unknown
/// name, a value of the wrong type or outside the parameter's min/max.
std::map<std::string, nlohmann::json> resolve_parameters(const Procedure& procedure,
                                                         const Overrides& overrides);

/// The flat list of steps: loops unrolled, references resolved, rate steps' rest_after set.
/// Throws ProcedureError listing every violation of the override checks and of the value rules
/// (non-positive durations, soak timeout shorter than stable time, empty loops, a reference to
/// a value of the wrong type, ...). Station limits are checked by make_plan().
std::vector<Step> expand(const Procedure& procedure, const Overrides& overrides = {});

/// Like expand() but never throws for rule breaks: appends them to `violations` and returns
/// every step (a value that breaks a rule is kept as given; a reference to something that is
/// not a number leaves its field 0). make_plan() uses it so that one call lists every problem.
std::vector<Step> expand_collecting(const Procedure& procedure, const Overrides& overrides,
                                    std::vector<Violation>& violations);

/// An expansion larger than this is refused (a guard against runaway nested loops).
inline constexpr std::size_t kMaxExpandedSteps = 100000;

}  // namespace calstand::procedures

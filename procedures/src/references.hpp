#pragma once

// References in procedure fields: "${name}" (a parameter or an enclosing loop variable) and
// "-${name}" (its negation, the only arithmetic, so that one list of rates gives CW and CCW).
// Labels may contain ${name} anywhere; it is replaced by the value's text.

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace calstand::procedures::detail {

struct Reference {
  std::string name;
  bool negated = false;
  /// As written: "${name}" or "-${name}".
  std::string text() const { return (negated ? "-${" : "${") + name + "}"; }
};

/// The reference `value` holds, or nullopt when it is not a string of the form "${name}" or
/// "-${name}" with `name` an identifier.
std::optional<Reference> parse_reference(const nlohmann::json& value);

/// Names of every ${name} in `text`, in order.
std::vector<std::string> label_references(const std::string& text);

/// `text` with each ${name} replaced by format_value(lookup(name)); a name lookup does not know
/// (nullopt) is left as written.
std::string fill_label(
    const std::string& text,
    const std::function<std::optional<nlohmann::json>(const std::string&)>& lookup);

/// A number as people read it: `-40`, `0.5`, `1e-05` (integral values without a decimal point).
std::string format_number(double x);

/// A value as people read it in labels and messages: numbers in shortest form (`-40`, `0.5`),
/// strings without quotes, lists as `[-40, 25, 85]`.
std::string format_value(const nlohmann::json& value);

/// A value as messages quote it: like format_value but strings in double quotes.
std::string quote_value(const nlohmann::json& value);

}  // namespace calstand::procedures::detail

namespace calstand::procedures {
struct Step;
}

namespace calstand::procedures::detail {

/// How a message shows the value of a step's field: `220`, or `${rate} = 220` when the field was
/// given by reference (Step::references).
std::string shown_value(const Step& step, const std::string& field, double value);

}  // namespace calstand::procedures::detail

#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>

namespace calstand::core {

/// Base dimensions a unit can carry. Angle is a dimension on purpose: it keeps deg/s from
/// silently becoming 1/s (Hz), a classic datasheet slip. Because of that the only
/// dimensionless units are the ratios (ppm, ppb, %, the empty unit), so "a ratio converts
/// only to another ratio" needs no flag of its own: it is the dimensions-must-match rule.
enum class BaseDimension { kAngle, kLength, kTime };
inline constexpr std::size_t kBaseDimensionCount = 3;

/// A unit: how many SI units (rad, m, s) one of it is, and its dimension. Exponents are kept
/// in halves so that sqrt(h) and sqrt(Hz), everywhere in noise specifications, stay exact.
struct Unit {
  double scale = 1.0;  ///< value of one of this unit in the coherent SI unit of its dimension
  /// Twice the exponent of each BaseDimension, indexed by its enum value: deg/sqrt(h) is
  /// {2, 0, -1} (angle^1 time^-1/2).
  std::array<int, kBaseDimensionCount> twice_exponent{};

  bool same_dimension(const Unit& other) const { return twice_exponent == other.twice_exponent; }
  bool dimensionless() const { return twice_exponent == decltype(twice_exponent){}; }
};

/// A number with the unit it was written in.
struct Quantity {
  double value = 0.0;
  Unit unit;
  std::string unit_text;  ///< the unit as written, outer whitespace trimmed; empty if none
};

/// Parses a unit expression such as "deg/s/sqrt(Hz)", "ug/sqrt(Hz)", "m/s^2", "deg/h/sqrt(h)".
///
/// Grammar: `*` and `/` (left to right), `^` with an exponent that is a multiple of 1/2 (`s^2`,
/// `s^-1`, `s^(3/2)`, `Hz^0.5`), parentheses, `sqrt(...)`, the number 1 (as in "1/s"), and these
/// names (case matters):
///   angle  rad mrad urad deg arcmin arcsec rev
///   time   s ms us min h hr;  Hz kHz (1/s)
///   length m mm um km
///   accel  g mg ug (standard gravity 9.80665 m/s^2, not gram), Gal mGal uGal
///   ratio  ppm ppb %
/// Whitespace between tokens is ignored. Datasheet spellings copied as UTF-8 are accepted too:
/// µ or μ for u, ° for deg, √ for sqrt of the following factor ("µg/√Hz", "°/√h").
/// The empty expression is the dimensionless unit 1.
///
/// Throws InputError naming the text and the 1-based column (in characters) of the problem,
/// e.g. `unit "deg/sqrt(hr" at column 12: expected ')'`, for a syntax error, an unknown name or
/// an exponent that is not a multiple of 1/2.
Unit parse_unit(std::string_view text);

/// Parses a number followed by an optional unit: "0.15 deg/sqrt(h)", "50ug/sqrt(Hz)", "100 ppm",
/// "1e-3". Throws InputError (as parse_unit, with `quantity "..."` and columns in the whole text)
/// when the number is missing, not finite, or the unit does not parse.
Quantity parse_quantity(std::string_view text);

/// `value` in unit `from` expressed in unit `to`. Throws InputError if either unit does not
/// parse, or if their dimensions differ, e.g. `cannot convert deg/sqrt(h) [angle time^-1/2] to
/// m/s [length time^-1]: dimensions differ`.
double convert(double value, std::string_view from, std::string_view to);

/// As above, for parsed units. Throws InputError if the dimensions differ.
double convert(double value, const Unit& from, const Unit& to);

/// The dimension in words, e.g. "angle time^-1/2", "length time^-2"; "dimensionless" for ratios.
std::string describe_dimension(const Unit& unit);

/// The coherent SI unit of `unit`'s dimension, written so that parse_unit reads it back with
/// scale 1: "rad/sqrt(s)", "m/s^2", "rad/s^(3/2)"; "" for dimensionless.
std::string si_unit(const Unit& unit);

// Conversion factors that other code states often enough to deserve names. Each equals the
// corresponding convert() call (checked in tests/unit/core/units_test.cpp).
/// 1 arcsec in rad: the usual unit of misalignment and of table axis errors.
inline constexpr double kArcsecToRad = 3.14159265358979323846 / (180.0 * 3600.0);
/// 1 deg/h in rad/s: the usual unit of gyro bias.
inline constexpr double kDegPerHourToRadPerS = 3.14159265358979323846 / (180.0 * 3600.0);
/// 1 deg/sqrt(h) in rad/sqrt(s), the angle random walk unit; sqrt(3600 s) = 60 sqrt(s).
inline constexpr double kDegPerSqrtHourToRadPerSqrtS = 3.14159265358979323846 / (180.0 * 60.0);
/// 1 ug in m/s^2: the usual unit of accelerometer bias and noise density (ug/sqrt(Hz)).
inline constexpr double kMicroGToMps2 = 9.80665e-6;

}  // namespace calstand::core

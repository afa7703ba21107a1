#include "core/units.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <system_error>
#include <utility>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"

namespace calstand::core {
namespace {

struct NamedUnit {
  std::string_view name;
  double scale;  // SI value of one
  int angle;     // exponents (whole; sqrt only appears in expressions)
  int length;
  int time;
};

// Acceleration units are length time^-2 with no mass anywhere, so "g" can only mean standard
// gravity; gram would need a mass dimension no inertial datasheet uses.
const NamedUnit kNamedUnits[] = {
    {"rad", 1.0, 1, 0, 0},
    {"mrad", 1e-3, 1, 0, 0},
    {"urad", 1e-6, 1, 0, 0},
    {"deg", kDegToRad, 1, 0, 0},
    {"arcmin", kDegToRad / 60.0, 1, 0, 0},
    {"arcsec", kDegToRad / 3600.0, 1, 0, 0},
    {"rev", 2.0 * kPi, 1, 0, 0},
    {"s", 1.0, 0, 0, 1},
    {"ms", 1e-3, 0, 0, 1},
    {"us", 1e-6, 0, 0, 1},
    {"min", 60.0, 0, 0, 1},
    {"h", 3600.0, 0, 0, 1},
    {"hr", 3600.0, 0, 0, 1},
    {"Hz", 1.0, 0, 0, -1},
    {"kHz", 1e3, 0, 0, -1},
    {"m", 1.0, 0, 1, 0},
    {"mm", 1e-3, 0, 1, 0},
    {"um", 1e-6, 0, 1, 0},
    {"km", 1e3, 0, 1, 0},
    {"g", kStandardGravity, 0, 1, -2},
    {"mg", kStandardGravity * 1e-3, 0, 1, -2},
    {"ug", kStandardGravity * 1e-6, 0, 1, -2},
    {"Gal", 1e-2, 0, 1, -2},
    {"mGal", 1e-5, 0, 1, -2},
    {"uGal", 1e-8, 0, 1, -2},
    {"ppm", 1e-6, 0, 0, 0},
    {"ppb", 1e-9, 0, 0, 0},
    {"%", 1e-2, 0, 0, 0},
};

// UTF-8 spellings found in datasheets copied as text.
constexpr std::string_view kMicroSign = "\xC2\xB5";       // U+00B5
constexpr std::string_view kGreekMu = "\xCE\xBC";         // U+03BC
constexpr std::string_view kDegreeSign = "\xC2\xB0";      // U+00B0
constexpr std::string_view kSquareRoot = "\xE2\x88\x9A";  // U+221A

// Deeper nesting than this is no unit anyone writes; the cap keeps hostile input such as
// "((((...", from overflowing the stack of the recursive descent.
constexpr int kMaxNesting = 64;
// Keeps pow() of any scale finite and the halves arithmetic far from int overflow.
constexpr double kMaxAbsExponent = 16.0;

bool ascii_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }

bool ascii_iequal(std::string_view a, std::string_view b) {
  auto lower = [](char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; };
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                            [&](char x, char y) { return lower(x) == lower(y); });
}

Unit multiply(const Unit& a, const Unit& b, int sign) {
  Unit r;
  r.scale = sign > 0 ? a.scale * b.scale : a.scale / b.scale;
  for (std::size_t i = 0; i < kBaseDimensionCount; ++i) {
    r.twice_exponent[i] = a.twice_exponent[i] + sign * b.twice_exponent[i];
  }
  return r;
}

// Exponents to `halves`/2. Returns nullopt when a base exponent would leave the half grid
// (sqrt(sqrt(Hz))).
std::optional<Unit> power(const Unit& u, int halves) {
  Unit r;
  r.scale = std::pow(u.scale, halves / 2.0);
  for (std::size_t i = 0; i < kBaseDimensionCount; ++i) {
    const int product = u.twice_exponent[i] * halves;
    if (product % 2 != 0) return std::nullopt;
    r.twice_exponent[i] = product / 2;
  }
  return r;
}

std::string_view trim(std::string_view s) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return s;
}

// Recursive descent over `text_` from `pos_`:
//   expression := term (('*' | '/') term)*
//   term       := factor ('^' exponent)?
//   factor     := '(' expression ')' | 'sqrt' '(' expression ')' | '√' factor | name | '1'
//   exponent   := signed-number | '(' signed-number ('/' number)? ')'
class UnitParser {
 public:
  // `kind` ("unit" or "quantity") names what the user wrote in error messages; columns count
  // from the start of `text`, so a quantity's unit errors point into the whole quantity.
  UnitParser(std::string_view text, std::size_t begin, std::string_view kind)
      : text_(text), pos_(begin), kind_(kind) {}

  Unit parse_all() {
    skip_space();
    if (at_end()) return Unit{};
    Unit u = expression();
    skip_space();
    if (!at_end()) {
      if (starts_factor()) fail(pos_, "expected '*' or '/' between units");
      fail(pos_, peek() == ')' ? "unmatched ')'" : "expected '*', '/' or end of unit");
    }
    return u;
  }

  [[noreturn]] void fail(std::size_t pos, std::string_view why) const {
    // Columns count characters, not bytes, so that "µg/√Hz" errors point where the user looks.
    std::size_t column = 1;
    for (std::size_t i = 0; i < pos && i < text_.size(); ++i) {
      if ((static_cast<unsigned char>(text_[i]) & 0xC0) != 0x80) ++column;
    }
    throw InputError(fmt::format("{} \"{}\" at column {}", kind_, text_, column), std::string(why));
  }

 private:
  Unit expression() {
    Unit u = term();
    for (;;) {
      skip_space();
      if (consume("*")) {
        u = multiply(u, term(), +1);
      } else if (consume("/")) {
        u = multiply(u, term(), -1);
      } else {
        return u;
      }
    }
  }

  Unit term() {
    skip_space();
    const std::size_t start = pos_;
    Unit u = factor();
    skip_space();
    if (!consume("^")) return u;
    const int halves = exponent_halves();
    auto r = power(u, halves);
    if (!r) fail(start, "exponent leaves a dimension off multiples of 1/2");
    after_exponent_ = true;
    return *r;
  }

  Unit factor() {
    skip_space();
    const bool after_exponent = std::exchange(after_exponent_, false);
    const std::size_t start = pos_;
    if (at_end()) fail(pos_, "expected a unit name, '(' or 'sqrt('");
    if (consume("(")) {
      Nesting guard(*this, start);
      Unit u = expression();
      expect_close();
      return u;
    }
    if (consume(kSquareRoot)) {
      Nesting guard(*this, start);
      return square_root(factor(), start);
    }
    if (peek() >= '0' && peek() <= '9') {
      double v = 0.0;
      const auto [end, ec] = std::from_chars(text_.data() + pos_, text_.data() + text_.size(), v);
      if (ec == std::errc{} && v == 1.0) {
        pos_ = static_cast<std::size_t>(end - text_.data());
        return Unit{};
      }
      fail(start, after_exponent
                      ? "a number here reads as a unit; write a fractional exponent as ^(1/2)"
                      : "the only number allowed in a unit is 1, as in 1/s");
    }
    const std::string name = read_name();
    if (name.empty()) fail(start, "expected a unit name, '(' or 'sqrt('");
    if (name == "sqrt") {
      skip_space();
      if (!consume("(")) fail(pos_, "expected '(' after sqrt");
      Nesting guard(*this, start);
      Unit inner = expression();
      expect_close();
      return square_root(inner, start);
    }
    for (const auto& n : kNamedUnits) {
      if (n.name == name) {
        return Unit{n.scale, {2 * n.angle, 2 * n.length, 2 * n.time}};
      }
    }
    for (const auto& n : kNamedUnits) {
      if (ascii_iequal(n.name, name)) {
        fail(start, fmt::format("unknown unit \"{}\" (did you mean \"{}\"?)", name, n.name));
      }
    }
    fail(start, fmt::format("unknown unit \"{}\"", name));
  }

  int exponent_halves() {
    skip_space();
    const std::size_t start = pos_;
    const bool parenthesized = consume("(");
    double value = signed_number();
    if (parenthesized) {
      skip_space();
      if (consume("/")) {
        const double denominator = signed_number();
        if (denominator == 0.0) fail(start, "exponent divides by zero");
        value /= denominator;
      }
      expect_close();
    }
    const double halves = std::round(2.0 * value);
    if (std::abs(2.0 * value - halves) > 1e-9) fail(start, "exponent must be a multiple of 1/2");
    if (std::abs(value) > kMaxAbsExponent) fail(start, "exponent is too large");
    return static_cast<int>(halves);
  }

  double signed_number() {
    skip_space();
    const std::size_t start = pos_;
    bool negative = false;
    if (consume("-")) {
      negative = true;
    } else {
      consume("+");
    }
    double v = 0.0;
    // from_chars would also take "inf" and "nan"; an exponent must start with a digit or '.'.
    if (!at_end() && ((peek() >= '0' && peek() <= '9') || peek() == '.')) {
      const auto [end, ec] = std::from_chars(text_.data() + pos_, text_.data() + text_.size(), v,
                                             std::chars_format::fixed);
      if (ec == std::errc{}) {
        pos_ = static_cast<std::size_t>(end - text_.data());
        return negative ? -v : v;
      }
    }
    fail(start, "expected an exponent");
  }

  Unit square_root(const Unit& u, std::size_t start) const {
    auto r = power(u, 1);
    if (!r) fail(start, "sqrt leaves a dimension off multiples of 1/2");
    return *r;
  }

  // Letters, '%', µ/μ (read as u) and ° (read as deg), so "°/h" and "µg" look up the table.
  std::string read_name() {
    std::string name;
    while (!at_end()) {
      if (ascii_letter(peek()) || peek() == '%') {
        name += peek();
        ++pos_;
      } else if (consume(kMicroSign) || consume(kGreekMu)) {
        name += 'u';
      } else if (consume(kDegreeSign)) {
        name += "deg";
      } else {
        break;
      }
    }
    return name;
  }

  bool starts_factor() const {
    const std::string_view rest = text_.substr(pos_);
    return ascii_letter(peek()) || peek() == '%' || peek() == '(' ||
           (peek() >= '0' && peek() <= '9') || rest.starts_with(kMicroSign) ||
           rest.starts_with(kGreekMu) || rest.starts_with(kDegreeSign) ||
           rest.starts_with(kSquareRoot);
  }

  void expect_close() {
    skip_space();
    if (!consume(")")) fail(pos_, "expected ')'");
  }

  void skip_space() {
    while (!at_end() && (peek() == ' ' || peek() == '\t')) ++pos_;
  }
  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }
  bool consume(std::string_view token) {
    if (!text_.substr(pos_).starts_with(token)) return false;
    pos_ += token.size();
    return true;
  }

  struct Nesting {
    Nesting(UnitParser& p, std::size_t at) : parser(p) {
      if (++parser.depth_ > kMaxNesting) parser.fail(at, "nesting is too deep");
    }
    ~Nesting() { --parser.depth_; }
    Nesting(const Nesting&) = delete;
    Nesting& operator=(const Nesting&) = delete;
    UnitParser& parser;
  };

  std::string_view text_;
  std::size_t pos_;
  std::string_view kind_;
  int depth_ = 0;
  bool after_exponent_ = false;  // lets "s^-1/2" get a hint instead of a bare "unknown"
};

std::string format_exponent(int twice) {
  if (twice % 2 == 0) return twice / 2 == 1 ? "" : fmt::format("^{}", twice / 2);
  return fmt::format("^{}/2", twice);
}

std::string shown(std::string_view unit_text) {
  const std::string_view t = trim(unit_text);
  return t.empty() ? std::string("1") : std::string(t);
}

[[noreturn]] void throw_dimension_mismatch(std::string_view from_text, const Unit& from,
                                           std::string_view to_text, const Unit& to) {
  constexpr auto kAngle = static_cast<std::size_t>(BaseDimension::kAngle);
  Unit from_without_angle = from;
  Unit to_without_angle = to;
  from_without_angle.twice_exponent[kAngle] = 0;
  to_without_angle.twice_exponent[kAngle] = 0;
  // deg/s vs 1/s is the mistake angle-as-a-dimension exists to catch; say so, since many
  // people treat radians as dimensionless.
  const char* hint = from_without_angle.same_dimension(to_without_angle)
                         ? " (only in angle, which counts as a dimension here)"
                         : "";
  throw InputError(
      "", fmt::format("cannot convert {} [{}] to {} [{}]: dimensions differ{}", shown(from_text),
                      describe_dimension(from), shown(to_text), describe_dimension(to), hint));
}

}  // namespace

Unit parse_unit(std::string_view text) { return UnitParser(text, 0, "unit").parse_all(); }

Quantity parse_quantity(std::string_view text) {
  UnitParser errors(text, 0, "quantity");
  std::size_t pos = 0;
  while (pos < text.size() && (text[pos] == ' ' || text[pos] == '\t')) ++pos;
  const std::size_t number_start = pos;
  bool negative = false;
  if (pos < text.size() && (text[pos] == '-' || text[pos] == '+')) {
    negative = text[pos] == '-';
    ++pos;
  }
  // from_chars also reads "inf" and "nan"; a datasheet value starts with a digit or '.'.
  if (pos >= text.size() || !((text[pos] >= '0' && text[pos] <= '9') || text[pos] == '.')) {
    errors.fail(number_start, "expected a number");
  }
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data() + pos, text.data() + text.size(), value);
  if (ec == std::errc::result_out_of_range) errors.fail(number_start, "number is out of range");
  if (ec != std::errc{}) errors.fail(number_start, "expected a number");
  const auto unit_begin = static_cast<std::size_t>(end - text.data());

  Quantity q;
  q.value = negative ? -value : value;
  q.unit = UnitParser(text, unit_begin, "quantity").parse_all();
  q.unit_text = std::string(trim(text.substr(unit_begin)));
  return q;
}

double convert(double value, const Unit& from, const Unit& to) {
  if (!from.same_dimension(to)) throw_dimension_mismatch(si_unit(from), from, si_unit(to), to);
  return value * (from.scale / to.scale);
}

double convert(double value, std::string_view from, std::string_view to) {
  const Unit f = parse_unit(from);
  const Unit t = parse_unit(to);
  if (!f.same_dimension(t)) throw_dimension_mismatch(from, f, to, t);
  return value * (f.scale / t.scale);
}

std::string describe_dimension(const Unit& unit) {
  static constexpr std::string_view kNames[kBaseDimensionCount] = {"angle", "length", "time"};
  std::string out;
  for (std::size_t i = 0; i < kBaseDimensionCount; ++i) {
    const int twice = unit.twice_exponent[i];
    if (twice == 0) continue;
    if (!out.empty()) out += ' ';
    out += kNames[i];
    out += format_exponent(twice);
  }
  return out.empty() ? "dimensionless" : out;
}

std::string si_unit(const Unit& unit) {
  static constexpr std::string_view kSymbols[kBaseDimensionCount] = {"rad", "m", "s"};
  // A base with exponent |twice|/2 written so that parse_unit reads it back.
  auto factor = [](std::string_view symbol, int twice) {
    if (twice == 1) return fmt::format("sqrt({})", symbol);
    if (twice % 2 != 0) return fmt::format("{}^({}/2)", symbol, twice);
    return twice == 2 ? std::string(symbol) : fmt::format("{}^{}", symbol, twice / 2);
  };
  std::string numerator;
  std::string denominator;
  for (std::size_t i = 0; i < kBaseDimensionCount; ++i) {
    const int twice = unit.twice_exponent[i];
    if (twice > 0) numerator += (numerator.empty() ? "" : "*") + factor(kSymbols[i], twice);
    if (twice < 0) denominator += "/" + factor(kSymbols[i], -twice);
  }
  if (numerator.empty() && !denominator.empty()) numerator = "1";
  return numerator + denominator;
}

}  // namespace calstand::core

#include "core/units.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace calstand::core {
namespace {

// Relative comparison: conversion factors span 1e-9 to 1e4, so an absolute tolerance would be
// either meaningless or too strict.
void expect_rel(double actual, double expected, double rel = 1e-12) {
  EXPECT_NEAR(actual, expected, std::abs(expected) * rel) << "expected " << expected;
}

// The message a call throws, or "" if it does not throw InputError.
template <class F>
std::string thrown_message(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

constexpr double kPiTest = 3.14159265358979323846;

TEST(Units, AngleRandomWalkPerSqrtHourIsOneSixtiethPerSqrtSecond) {
  // sqrt(1 h) = sqrt(3600 s) = 60 sqrt(s), so 1 deg/sqrt(h) = 1/60 deg/sqrt(s).
  expect_rel(convert(1.0, "deg/sqrt(h)", "deg/sqrt(s)"), 1.0 / 60.0);
  // deg/s/sqrt(Hz) = deg s^-1 s^1/2 = deg/sqrt(s): the density and the random walk are one unit.
  expect_rel(convert(1.0, "deg/sqrt(h)", "deg/s/sqrt(Hz)"), 1.0 / 60.0);
  // 0.15 / 60 = 0.0025.
  expect_rel(convert(0.15, "deg/sqrt(h)", "deg/s/sqrt(Hz)"), 0.0025);
  // And back: 1e-3 deg/s/sqrt(Hz) * 60 = 0.06 deg/sqrt(h).
  expect_rel(convert(1e-3, "deg/s/sqrt(Hz)", "deg/sqrt(h)"), 0.06);
}

TEST(Units, GyroBiasInDegPerHour) {
  // 1 deg/h = (pi/180 rad) / (3600 s) = 4.8481368e-6 rad/s.
  expect_rel(convert(1.0, "deg/h", "rad/s"), 4.84813681109536e-6);
  EXPECT_NEAR(convert(1.0, "deg/h", "rad/s"), 4.8481368e-6, 1e-13);
  // 10 deg/h = 10/3600 deg/s; "hr" is the same hour.
  expect_rel(convert(10.0, "deg/hr", "deg/s"), 10.0 / 3600.0);
}

TEST(Units, AccelerometerNoiseDensityAndVelocityRandomWalk) {
  // 50 ug = 50 * 9.80665e-6 m/s^2 = 4.903325e-4 m/s^2; sqrt(Hz) has scale 1.
  expect_rel(convert(50.0, "ug/sqrt(Hz)", "m/s^2/sqrt(Hz)"), 4.903325e-4);
  // m/s^2/sqrt(Hz) = m s^-3/2 = (m/s)/sqrt(s), and 1/sqrt(s) = 60/sqrt(h): x60.
  expect_rel(convert(50.0, "ug/sqrt(Hz)", "m/s/sqrt(h)"), 4.903325e-4 * 60.0);
  // 0.07 m/s/sqrt(h) = 0.07/60 m/s/sqrt(s) = 1.16667e-3 m/s^2/sqrt(Hz) = 118.96 ug/sqrt(Hz).
  expect_rel(convert(0.07, "m/s/sqrt(h)", "ug/sqrt(Hz)"), 0.07 / 60.0 / 9.80665e-6);
}

TEST(Units, AccelerationUnitsUseStandardGravityNotGram) {
  expect_rel(convert(1.0, "g", "m/s^2"), 9.80665);
  expect_rel(convert(1.0, "mg", "m/s^2"), 9.80665e-3);
  expect_rel(convert(200.0, "ug", "mg"), 0.2);
  // 1 Gal = 1 cm/s^2, so 1 mGal = 1e-5 m/s^2.
  expect_rel(convert(1.0, "mGal", "m/s^2"), 1e-5);
  // 5 mGal = 5e-5 m/s^2 = 5e-5 / 9.80665 g = 5.0986 ug.
  expect_rel(convert(5.0, "mGal", "ug"), 5e-5 / 9.80665e-6);
  expect_rel(convert(1.0, "uGal", "m/s^2"), 1e-8);
  EXPECT_EQ(describe_dimension(parse_unit("g")), "length time^-2");
}

TEST(Units, SmallAngles) {
  // 20 arcsec = 20 / 3600 deg = 20 pi / 648000 rad = 9.69627e-5 rad.
  expect_rel(convert(20.0, "arcsec", "rad"), 20.0 * kPiTest / 648000.0);
  EXPECT_NEAR(convert(20.0, "arcsec", "rad"), 9.69627e-5, 1e-10);
  expect_rel(convert(1.0, "arcmin", "arcsec"), 60.0);
  expect_rel(convert(1.0, "rev", "deg"), 360.0);
  expect_rel(convert(1.0, "mrad", "urad"), 1000.0);
}

TEST(Units, RatiosConvertAmongRatios) {
  // ppm and % are plain numbers: 100e-6 = 1e-4 = 0.01 %.
  expect_rel(convert(100.0, "ppm", ""), 1e-4);
  expect_rel(convert(100.0, "ppm", "%"), 0.01);
  expect_rel(convert(1.0, "ppm", "ppb"), 1000.0);
  // Hz * s cancels to a number as well.
  expect_rel(convert(2.0, "kHz*ms", ""), 2.0);
  EXPECT_EQ(describe_dimension(parse_unit("ppm")), "dimensionless");
}

TEST(Units, RateRandomWalk) {
  // deg/h/sqrt(h) = deg h^-3/2 and h^-3/2 = 3600^-3/2 s^-3/2 = s^-3/2 / 216000;
  // deg/s^2/sqrt(Hz) = deg s^-2 s^1/2 = deg s^-3/2. So 3 deg/h/sqrt(h) = 3/216000.
  EXPECT_EQ(describe_dimension(parse_unit("deg/h/sqrt(h)")), "angle time^-3/2");
  EXPECT_EQ(describe_dimension(parse_unit("deg/s^2/sqrt(Hz)")), "angle time^-3/2");
  expect_rel(convert(3.0, "deg/h/sqrt(h)", "deg/s^2/sqrt(Hz)"), 3.0 / 216000.0);
  expect_rel(convert(3.0, "deg/h/sqrt(h)", "rad/s^(3/2)"), 3.0 / 216000.0 * kPiTest / 180.0);
}

TEST(Units, ScaleAndDimensionOfParsedUnits) {
  const Unit arw = parse_unit("deg/sqrt(h)");
  expect_rel(arw.scale, kPiTest / 180.0 / 60.0);
  EXPECT_EQ(arw.twice_exponent, (std::array<int, 3>{2, 0, -1}));
  EXPECT_EQ(describe_dimension(arw), "angle time^-1/2");
  EXPECT_TRUE(parse_unit("").dimensionless());
  EXPECT_DOUBLE_EQ(parse_unit("   ").scale, 1.0);
  EXPECT_FALSE(parse_unit("rad").dimensionless());
}

TEST(Units, OperatorsAndPrecedence) {
  // '^' binds tighter than '/', and '/' runs left to right: m/s^2 = m/s/s = m/(s*s).
  const Unit a = parse_unit("m/s^2");
  EXPECT_TRUE(a.same_dimension(parse_unit("m/s/s")));
  EXPECT_TRUE(a.same_dimension(parse_unit("m/(s*s)")));
  EXPECT_FALSE(a.same_dimension(parse_unit("m/s*s")));  // (m/s)*s = m
  EXPECT_EQ(describe_dimension(parse_unit("(m/s)^2")), "length^2 time^-2");
  EXPECT_TRUE(parse_unit("1/s").same_dimension(parse_unit("Hz")));
  EXPECT_TRUE(parse_unit("s^-1").same_dimension(parse_unit("Hz")));
  // Fractional exponents: Hz^0.5 = Hz^(1/2) = sqrt(Hz), scale included (kHz^0.5 =
  // sqrt(1000)/s^1/2).
  EXPECT_TRUE(parse_unit("Hz^0.5").same_dimension(parse_unit("sqrt(Hz)")));
  expect_rel(parse_unit("kHz^(1/2)").scale, std::sqrt(1000.0));
  expect_rel(parse_unit("h^(3/2)").scale, 216000.0);
  expect_rel(convert(1.0, "min", "s"), 60.0);
  expect_rel(convert(1.0, "km", "mm"), 1e6);
  expect_rel(convert(1.0, "us", "ms"), 1e-3);
}

TEST(Units, ParsesQuantities) {
  const Quantity q = parse_quantity("0.15 deg/sqrt(h)");
  EXPECT_DOUBLE_EQ(q.value, 0.15);
  EXPECT_EQ(q.unit_text, "deg/sqrt(h)");
  EXPECT_EQ(describe_dimension(q.unit), "angle time^-1/2");

  const Quantity e = parse_quantity("1e-3 deg/s/sqrt(Hz)");
  EXPECT_DOUBLE_EQ(e.value, 1e-3);
  EXPECT_EQ(e.unit_text, "deg/s/sqrt(Hz)");

  const Quantity bare = parse_quantity("42");
  EXPECT_DOUBLE_EQ(bare.value, 42.0);
  EXPECT_TRUE(bare.unit.dimensionless());
  EXPECT_EQ(bare.unit_text, "");

  EXPECT_DOUBLE_EQ(parse_quantity("-2.5 deg/h").value, -2.5);
  EXPECT_DOUBLE_EQ(parse_quantity("+.5 g").value, 0.5);
  EXPECT_DOUBLE_EQ(parse_quantity("100 %").unit.scale, 0.01);
}

TEST(Units, ToleratesWhitespace) {
  const double expected = 0.15 * kPiTest / 180.0 / 60.0;
  for (const char* text : {"0.15deg/sqrt(h)", "0.15 deg / sqrt( h )", "  0.15\tdeg/sqrt (h)  ",
                           "0.15 deg/ sqrt(h ) "}) {
    SCOPED_TRACE(text);
    const Quantity q = parse_quantity(text);
    expect_rel(q.value * q.unit.scale, expected);
  }
  EXPECT_EQ(parse_quantity("0.15 deg / sqrt( h ) ").unit_text, "deg / sqrt( h )");
  expect_rel(convert(1.0, " m / s ^ 2 ", "mg"), 1.0 / 9.80665e-3);
}

TEST(Units, AcceptsDatasheetUtf8Spellings) {
  // µ (micro sign) and μ (Greek mu) for u, ° for deg, √ for sqrt of the next factor.
  expect_rel(convert(50.0, "\xC2\xB5g/\xE2\x88\x9AHz", "ug/sqrt(Hz)"), 50.0);
  expect_rel(convert(50.0, "\xCE\xBCg/\xE2\x88\x9A(Hz)", "ug/sqrt(Hz)"), 50.0);
  expect_rel(convert(0.15, "\xC2\xB0/\xE2\x88\x9Ah", "deg/sqrt(h)"), 0.15);
  expect_rel(convert(3.0, "\xC2\xB0/h/\xE2\x88\x9Ah", "deg/h/sqrt(h)"), 3.0);
}

TEST(Units, NamedConstantsAgreeWithConvert) {
  expect_rel(kArcsecToRad, convert(1.0, "arcsec", "rad"));
  expect_rel(kDegPerHourToRadPerS, convert(1.0, "deg/h", "rad/s"));
  expect_rel(kDegPerSqrtHourToRadPerSqrtS, convert(1.0, "deg/sqrt(h)", "rad/sqrt(s)"));
  expect_rel(kMicroGToMps2, convert(1.0, "ug", "m/s^2"));
}

TEST(Units, SiUnitReadsBackWithScaleOne) {
  EXPECT_EQ(si_unit(parse_unit("deg/sqrt(h)")), "rad/sqrt(s)");
  EXPECT_EQ(si_unit(parse_unit("ug")), "m/s^2");
  EXPECT_EQ(si_unit(parse_unit("deg/h/sqrt(h)")), "rad/s^(3/2)");
  EXPECT_EQ(si_unit(parse_unit("kHz")), "1/s");
  EXPECT_EQ(si_unit(parse_unit("ppm")), "");
  for (const char* text : {"deg/sqrt(h)", "ug/sqrt(Hz)", "deg/h/sqrt(h)", "m/s/sqrt(h)", "Hz",
                           "mm*arcsec^2", "sqrt(km)", "ppm"}) {
    SCOPED_TRACE(text);
    const Unit u = parse_unit(text);
    const Unit si = parse_unit(si_unit(u));
    EXPECT_TRUE(si.same_dimension(u));
    EXPECT_DOUBLE_EQ(si.scale, 1.0);
  }
}

TEST(UnitsErrors, MismatchedDimensionsNameBothUnits) {
  EXPECT_EQ(thrown_message([] { convert(1.0, "deg/sqrt(h)", "m/s"); }),
            "cannot convert deg/sqrt(h) [angle time^-1/2] to m/s [length time^-1]: dimensions "
            "differ");
  // Angle is a dimension: deg/s is not 1/s, and the message says that is the only difference.
  EXPECT_EQ(thrown_message([] { convert(1.0, "deg/s", "1/s"); }),
            "cannot convert deg/s [angle time^-1] to 1/s [time^-1]: dimensions differ (only in "
            "angle, which counts as a dimension here)");
  EXPECT_NE(thrown_message([] { convert(1.0, "deg/s", "Hz"); }), "");
  // A ratio converts to ratios only, not to an angle (nor the reverse).
  EXPECT_EQ(thrown_message([] { convert(100.0, "ppm", "rad"); }),
            "cannot convert ppm [dimensionless] to rad [angle]: dimensions differ (only in angle, "
            "which counts as a dimension here)");
  EXPECT_EQ(thrown_message([] { convert(1.0, "", "g"); }),
            "cannot convert 1 [dimensionless] to g [length time^-2]: dimensions differ");
  // The Unit overload names the SI units, having no text.
  EXPECT_EQ(thrown_message([] { convert(1.0, parse_unit("deg/h"), parse_unit("g")); }),
            "cannot convert rad/s [angle time^-1] to m/s^2 [length time^-2]: dimensions differ");
  // Sanity: thrown_message reports "" when nothing is thrown, so the checks above can fail.
  EXPECT_EQ(thrown_message([] { convert(1.0, "deg/s", "rad/s"); }), "");
}

TEST(UnitsErrors, UnknownNamesArePointedAt) {
  EXPECT_EQ(thrown_message([] { parse_unit("deg/hz"); }),
            "unit \"deg/hz\" at column 5: unknown unit \"hz\" (did you mean \"Hz\"?)");
  EXPECT_EQ(thrown_message([] { parse_unit("furlong/s"); }),
            "unit \"furlong/s\" at column 1: unknown unit \"furlong\"");
  // Nanogram-or-nano-g is ambiguous enough that it is left out on purpose.
  EXPECT_EQ(thrown_message([] { parse_quantity("5 ng"); }),
            "quantity \"5 ng\" at column 3: unknown unit \"ng\"");
  // Columns count characters: µ and √ are two and three bytes but one column each.
  EXPECT_EQ(thrown_message([] { parse_unit("\xC2\xB5g/\xE2\x88\x9Ahz"); }),
            "unit \"\xC2\xB5g/\xE2\x88\x9Ahz\" at column 5: unknown unit \"hz\" (did you mean "
            "\"Hz\"?)");
}

TEST(UnitsErrors, MalformedSyntaxIsPointedAt) {
  EXPECT_EQ(thrown_message([] { parse_unit("deg/sqrt(hr"); }),
            "unit \"deg/sqrt(hr\" at column 12: expected ')'");
  EXPECT_EQ(thrown_message([] { parse_unit("deg/"); }),
            "unit \"deg/\" at column 5: expected a unit name, '(' or 'sqrt('");
  EXPECT_EQ(thrown_message([] { parse_unit("deg//s"); }),
            "unit \"deg//s\" at column 5: expected a unit name, '(' or 'sqrt('");
  EXPECT_EQ(thrown_message([] { parse_unit("sqrt h"); }),
            "unit \"sqrt h\" at column 6: expected '(' after sqrt");
  EXPECT_EQ(thrown_message([] { parse_unit("m s"); }),
            "unit \"m s\" at column 3: expected '*' or '/' between units");
  EXPECT_EQ(thrown_message([] { parse_unit("deg)"); }), "unit \"deg)\" at column 4: unmatched ')'");
  EXPECT_EQ(thrown_message([] { parse_unit("s^"); }),
            "unit \"s^\" at column 3: expected an exponent");
  EXPECT_EQ(thrown_message([] { parse_unit("s^(1/3)"); }),
            "unit \"s^(1/3)\" at column 3: exponent must be a multiple of 1/2");
  EXPECT_EQ(thrown_message([] { parse_unit("sqrt(sqrt(Hz))"); }),
            "unit \"sqrt(sqrt(Hz))\" at column 1: sqrt leaves a dimension off multiples of 1/2");
  EXPECT_EQ(thrown_message([] { parse_unit("s^-1/2"); }),
            "unit \"s^-1/2\" at column 6: a number here reads as a unit; write a fractional "
            "exponent as ^(1/2)");
  EXPECT_EQ(thrown_message([] { parse_unit("2/s"); }),
            "unit \"2/s\" at column 1: the only number allowed in a unit is 1, as in 1/s");
  EXPECT_NE(
      thrown_message([] { parse_unit(std::string(1000, '(') + "s" + std::string(1000, ')')); }),
      "");
}

TEST(UnitsErrors, QuantityNeedsAFiniteNumber) {
  EXPECT_EQ(thrown_message([] { parse_quantity("deg/s"); }),
            "quantity \"deg/s\" at column 1: expected a number");
  EXPECT_EQ(thrown_message([] { parse_quantity(""); }),
            "quantity \"\" at column 1: expected a number");
  EXPECT_EQ(thrown_message([] { parse_quantity("inf deg"); }),
            "quantity \"inf deg\" at column 1: expected a number");
  EXPECT_EQ(thrown_message([] { parse_quantity("1e999 deg"); }),
            "quantity \"1e999 deg\" at column 1: number is out of range");
  // Unit errors inside a quantity count columns in the whole text.
  EXPECT_EQ(thrown_message([] { parse_quantity("0.15 deg/sqrt(hr"); }),
            "quantity \"0.15 deg/sqrt(hr\" at column 17: expected ')'");
}

}  // namespace
}  // namespace calstand::core

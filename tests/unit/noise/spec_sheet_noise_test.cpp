// The simulator's spec-sheet IMUs (sim/specs: LN200- and ADIS16488-class) recorded at rest give
// back their sheets' noise figures through calstand noise-id: the terms the sheet has are
// selected and each figure the simulator's truth holds lies inside its 95 % interval.
#include <gtest/gtest.h>

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "noise/composite_noise.hpp"
#include "sim/imu_sim.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::solver {
namespace {

struct SpecCase {
  const char* name;
  const char* sheet;
  bool gyro;            // the z gyro, else the z accelerometer
  std::size_t samples;  // at the sheet's output rate
  // Samples averaged into one before the identification (a shorter record to fit; white,
  // flicker, Gauss-Markov and random-walk figures are kept).
  std::size_t block;
  // The first scale's averaging time [s]: above the sheet's output low-pass, which is not a
  // term of the model and lowers the first scales' variance (NoiseIdOptions::min_tau_s).
  double min_tau_s;
  bool expect_gauss_markov;  // false where the record cannot resolve the sheet's (see below)
};

void PrintTo(const SpecCase& c, std::ostream* os) { *os << c.name; }

// One channel of a unit drawn from the case's sheet, at rest, averaged in blocks.
std::vector<double> static_record(const sim::ImuTruth& truth, const SpecCase& c,
                                  std::uint64_t seed) {
  core::Site site;
  site.latitude_deg = 45.0;
  site.gravity_mps2 = 9.806;
  sim::ImuSim imu(truth, {}, site, Eigen::Vector2d::Zero(), seed);
  imu.power_on(0.0, true);
  const double dt = imu.sample_period_s();
  std::vector<double> out;
  out.reserve(c.samples / c.block);
  double sum = 0.0;
  for (std::size_t i = 0; i < c.samples; ++i) {
    const core::ImuSample s = imu.sample(static_cast<double>(i) * dt, {}, 25.0);
    sum += c.gyro ? s.gyro_dps.z() : s.accel_mps2.z();
    if ((i + 1) % c.block == 0) {
      out.push_back(sum / static_cast<double>(c.block));
      sum = 0.0;
    }
  }
  return out;
}

const NoiseModelTerm* find(const NoiseModel& m, NoiseKind kind) {
  for (const auto& t : m.terms) {
    if (t.kind == kind) return &t;
  }
  return nullptr;
}

class SpecSheetNoise : public ::testing::TestWithParam<SpecCase> {};

// Three units (seeds) per sheet: each figure inside its 95 % interval in at least 2 of the 3
// (a right interval misses twice in three with probability 0.7 %), the sheet's set of terms
// selected in at least 2 of 3.
TEST_P(SpecSheetNoise, FiguresInsideTheIntervals) {
  const SpecCase& c = GetParam();
  std::map<std::string, int> inside, seen;
  int right_set = 0;
  for (std::uint64_t seed : {3u, 4u, 5u}) {
    const sim::ImuTruth truth = sim::truth_from_spec(*sim::builtin_spec(c.sheet), c.sheet, seed);
    const sim::TriadNoise& n = c.gyro ? truth.gyro_noise : truth.accel_noise;
    NoiseIdOptions o;
    o.min_tau_s = c.min_tau_s;
    const NoiseModel m = identify_noise_model(
        static_record(truth, c, seed), truth.sample_rate_hz / static_cast<double>(c.block), o);
    std::vector<NoiseKind> expected{NoiseKind::kWhite};
    if (n.bias_instability.z() > 0.0) expected.push_back(NoiseKind::kFlicker);
    if (c.expect_gauss_markov) expected.push_back(NoiseKind::kGaussMarkov);
    if (n.random_walk.z() > 0.0) expected.push_back(NoiseKind::kRandomWalk);
    std::vector<NoiseKind> kinds;
    for (const auto& t : m.terms) kinds.push_back(t.kind);
    if (kinds != expected) continue;
    ++right_set;
    const auto check = [&](const std::string& figure, double truth_value, double lo, double hi) {
      ++seen[figure];
      inside[figure] += truth_value >= lo && truth_value <= hi ? 1 : 0;
    };
    const NoiseModelTerm* white = find(m, NoiseKind::kWhite);
    check("white density (ARW, VRW)", n.white.z(), white->value_lo, white->value_hi);
    if (const NoiseModelTerm* f = find(m, NoiseKind::kFlicker)) {
      check("bias instability", n.bias_instability.z(), f->value_lo, f->value_hi);
    }
    if (const NoiseModelTerm* g = find(m, NoiseKind::kGaussMarkov)) {
      check("bias variation sigma", n.gauss_markov_sigma.z(), g->value_lo, g->value_hi);
      check("bias variation tau", n.gauss_markov_tau_s, g->tau_lo_s, g->tau_hi_s);
    }
    if (const NoiseModelTerm* k = find(m, NoiseKind::kRandomWalk)) {
      check("random walk", n.random_walk.z(), k->value_lo, k->value_hi);
    }
  }
  EXPECT_GE(right_set, 2) << c.name << ": the sheet's terms selected in " << right_set << " of 3";
  for (const auto& [figure, count] : seen) {
    EXPECT_GE(inside[figure], 2) << c.name << " " << figure << ": inside in " << inside[figure]
                                 << " of " << count;
  }
}

// LN200-class gyro: ARW 0.07 deg/sqrt(h) and a bias variation of 0.35 deg/h over 100 s, 400 Hz
// with no output filter below Nyquist. The bias variation's Allan bump is a quarter of the
// white noise's variance at its peak (190 s): 175 min of record lower the objective by 7.3 with
// it, against a penalty of 10.1 for its two parameters, so no record of a few hours resolves
// it and only the ARW is checked (44 min, four samples averaged: 100 Hz).
// LN200-class accelerometer: 50 ug/sqrt(Hz) and 50 ug over 60 s, behind a 100 Hz low-pass
// (175 min, 32 averaged: 12.5 Hz, from 0.2 s). The 60 s time comes out 15 to 24 % short in
// these three units (45 to 51 s) where records simulated by composite_records.hpp of that
// length give -4 % on average: these three records carry about 20 % less long-scale variance
// than the truth states, about two standard errors (docs/noise-id.md, "Spec sheets").
// ADIS16488-class gyro: ARW 0.26 deg/sqrt(h), in-run bias stability 5.1 deg/h (the flicker
// floor), 2460 Hz behind a 330 Hz low-pass (7 min, sixteen averaged: 154 Hz, from 0.05 s).
INSTANTIATE_TEST_SUITE_P(
    Sheets, SpecSheetNoise,
    ::testing::Values(SpecCase{"ln200_gyro", "ln200", true, std::size_t{1} << 20, 4, 0.0, false},
                      SpecCase{"ln200_accel", "ln200", false, std::size_t{1} << 22, 32, 0.2, true},
                      SpecCase{"adis16488_gyro", "adis16488", true, std::size_t{1} << 20, 16, 0.05,
                               false}),
    [](const ::testing::TestParamInfo<SpecCase>& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace calstand::solver

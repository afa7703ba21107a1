// The acceptance table of issue 33 (docs/noise-id.md): GMWM noise identification and the
// Allan-line fit on composite models simulated by exact discrete recursions, many seeds and
// two lengths. A plain program printing a Markdown table:
//   calstand_noise_id_bench [SEEDS=10] [BOOTSTRAP=0]   (0: the asymptotic intervals, the default)
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "../tests/unit/noise/composite_records.hpp"
#include "noise/allan.hpp"
#include "noise/composite_noise.hpp"
#include "noise/noise_fit.hpp"

namespace {

using calstand::solver::NoiseKind;
constexpr double kFs = calstand::solver::testing::kCompositeRateHz;

using calstand::solver::testing::TrueTerm;

std::vector<double> simulate(const std::vector<TrueTerm>& truth, std::size_t n, unsigned seed) {
  return calstand::solver::testing::simulate_composite(truth, n, seed);
}

struct Scenario {
  std::string name;
  std::vector<TrueTerm> truth, extra;
  std::vector<NoiseKind> true_set;
};

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string pct(double v) { return std::isfinite(v) ? fmt::format("{:+.1f} %", 100.0 * v) : "-"; }

}  // namespace

int main(int argc, char** argv) {
  const unsigned seeds = argc > 1 ? static_cast<unsigned>(std::atoi(argv[1])) : 10u;
  const std::size_t bootstrap = argc > 2 ? static_cast<std::size_t>(std::atoi(argv[2])) : 0u;
  using K = NoiseKind;
  std::vector<TrueTerm> bank;
  for (double tc = 0.05; tc < 5000.0; tc *= 2.0) bank.push_back({K::kGaussMarkov, 0.0011, tc});
  const std::vector<Scenario> scenarios{
      {"white + GM + RW",
       {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 2.0}, {K::kRandomWalk, 5e-4}},
       {},
       {K::kWhite, K::kGaussMarkov, K::kRandomWalk}},
      {"white + two GM",
       {{K::kWhite, 0.005}, {K::kGaussMarkov, 0.004, 0.5}, {K::kGaussMarkov, 0.003, 100.0}},
       {},
       {K::kWhite, K::kGaussMarkov, K::kGaussMarkov}},
      {"white + RW", {{K::kWhite, 0.005}, {K::kRandomWalk, 5e-4}}, {}, {K::kWhite, K::kRandomWalk}},
      {"white + flicker (GM bank) + RW",
       {{K::kWhite, 0.005}, {K::kRandomWalk, 5e-4}},
       bank,
       {K::kWhite, K::kFlicker, K::kRandomWalk}},
  };
  fmt::print(
      "| model | samples at 100 Hz | true set selected | truth in 95 % CI | GM sigma err "
      "(median abs) | GM tau err | white N err (median signed) | K err | Allan-line N err | "
      "Allan-line K err | Allan-line truth in +-1.96 sigma | s per record |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  unsigned model_index = 0;
  for (const Scenario& s : scenarios) {
    ++model_index;
    for (std::size_t n : {std::size_t{1} << 18, std::size_t{1} << 19, std::size_t{1} << 20}) {
      int selected = 0, covered = 0, checked = 0, allan_covered = 0, allan_checked = 0;
      std::vector<double> gs, gt, wn, kk, an, ak;
      double seconds = 0.0;
      for (unsigned seed = 1; seed <= seeds; ++seed) {
        std::vector<TrueTerm> all = s.truth;
        all.insert(all.end(), s.extra.begin(), s.extra.end());
        // Seeds apart from the test's (composite_noise_test.cpp), one per model and length.
        const std::vector<double> y =
            simulate(all, n, 1000u * seed + static_cast<unsigned>(n % 997) + 7u * model_index);
        calstand::solver::NoiseIdOptions o;
        o.bootstrap = bootstrap;
        const auto t0 = std::chrono::steady_clock::now();
        const auto m = calstand::solver::identify_noise_model(y, kFs, o);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::vector<K> got;
        for (const auto& t : m.terms) got.push_back(t.kind);
        // The Allan-line fit of the same record (calstand noise's: dense taus, IEEE 952 terms).
        calstand::solver::AllanOptions ao;
        ao.taus = calstand::solver::TauSet::parse("dense");
        const auto curve = calstand::solver::allan(y, kFs, ao);
        const auto lines = calstand::solver::fit_noise_terms(curve);
        for (const TrueTerm& t : s.truth) {
          const calstand::solver::NoiseTerm* a = t.kind == K::kWhite ? &lines.random_walk
                                                 : t.kind == K::kRandomWalk
                                                     ? &lines.rate_random_walk
                                                     : nullptr;
          if (!a) continue;
          const double v = a->resolved ? a->value : 0.0;
          (t.kind == K::kWhite ? an : ak).push_back(v / t.value - 1.0);
          ++allan_checked;
          allan_covered += a->resolved && std::abs(a->value - t.value) <= 1.96 * a->sigma ? 1 : 0;
        }
        if (got != s.true_set) continue;
        ++selected;
        std::vector<TrueTerm> truth = s.truth;
        std::sort(truth.begin(), truth.end(), [](const TrueTerm& a, const TrueTerm& b) {
          return a.kind != b.kind ? a.kind < b.kind : a.tau_s < b.tau_s;
        });
        std::size_t k = 0;
        for (const auto& e : m.terms) {
          if (e.kind == K::kFlicker) continue;
          const TrueTerm& t = truth[k++];
          ++checked;
          covered += t.value >= e.value_lo && t.value <= e.value_hi ? 1 : 0;
          if (e.kind == K::kGaussMarkov) {
            ++checked;
            covered += t.tau_s >= e.tau_lo_s && t.tau_s <= e.tau_hi_s ? 1 : 0;
            gs.push_back(std::abs(e.value / t.value - 1.0));
            gt.push_back(std::abs(e.tau_s / t.tau_s - 1.0));
          }
          if (e.kind == K::kWhite) wn.push_back(e.value / t.value - 1.0);
          if (e.kind == K::kRandomWalk) kk.push_back(e.value / t.value - 1.0);
        }
      }
      fmt::print(
          "| {} | {} | {} of {} | {} of {} | {} | {} | {} | {} | {} | {} | {} of {} | {:.2f} |\n",
          s.name, n, selected, seeds, covered, checked, pct(median(gs)), pct(median(gt)),
          pct(median(wn)), pct(median(kk)), pct(median(an)), pct(median(ak)), allan_covered,
          allan_checked, seconds / seeds);
      std::fflush(stdout);
    }
  }
  return 0;
}

// Probe (temporary): prints the estimators on the SP 1065 test set.
#include "solver/total_deviation.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <vector>

namespace calstand::solver {
namespace {

std::vector<double> nist_set() {
  std::vector<double> y;
  std::uint64_t n = 1234567890;
  y.push_back(static_cast<double>(n) / 2147483647.0);
  while (y.size() < 1000) {
    n = (16807 * n) % 2147483647;
    y.push_back(static_cast<double>(n) / 2147483647.0);
  }
  return y;
}

TEST(TotalProbe, Print) {
  const auto y = nist_set();
  for (const char* k : {"totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theobr", "theoh"}) {
    for (int a : {99, 0, 1}) {
      TotalOptions o;
      o.kind = *parse_total_kind(k);
      o.taus = TauSet::parse(o.kind == TotalKind::kTheo1 ? "7.5,15,30,75,151.5,300,748.5" : "octave");
      if (a != 99) o.alpha = a;
      const auto r = total_deviation(y, 1.0, o);
      for (const auto& p : r.points)
        std::printf("%s a=%d m=%zu tau=%g n=%zu alpha=%d dev=%.5e lo=%.5e hi=%.5e edf=%.4g\n", k, a, p.m,
                    p.tau_s, p.terms, p.alpha, p.deviation, p.lo, p.hi, p.edf);
    }
  }
}

}  // namespace
}  // namespace calstand::solver

#include "sim/random_engine.hpp"

#include <gtest/gtest.h>

#include <random>

namespace calstand::sim {
namespace {

static_assert(std::uniform_random_bit_generator<Xoshiro256pp>);

TEST(Xoshiro256pp, FollowsTheAlgorithmStepByStep) {
  // State {1, 2, 3, 4} worked by hand from the definition:
  // out0 = rotl(1 + 4, 23) + 1 = 5 * 2^23 + 1 = 41943041.
  // Update: t = 2 << 17 = 262144; s2 ^= s0 -> 2; s3 ^= s1 -> 6; s1 ^= s2 -> 0; s0 ^= s3 -> 7;
  // s2 ^= t -> 262146; s3 = rotl(6, 45) = 6 * 2^45.
  // out1 = rotl(7 + 6 * 2^45, 23) + 7: the low part shifts to 7 * 2^23 and the high part
  // 6 * 2^45 rotates round the top to 6 * 2^(45 + 23 - 64) = 96; plus s0 = 7.
  auto e = Xoshiro256pp::from_state(1, 2, 3, 4);
  EXPECT_EQ(e(), 41943041u);
  EXPECT_EQ(e(), 7u * (1u << 23) + 96u + 7u);
}

TEST(Xoshiro256pp, SeedsAreDeterministicAndDistinct) {
  Xoshiro256pp a(5), b(5), c(6);
  for (int k = 0; k < 100; ++k) {
    const auto x = a();
    EXPECT_EQ(x, b());
    EXPECT_NE(x, c());
  }
}

TEST(Xoshiro256pp, UniformDoublesHaveTheRightMoments) {
  Xoshiro256pp e(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 200000;
  double sum = 0.0, sum_sq = 0.0;
  for (int k = 0; k < n; ++k) {
    const double x = u(e);
    sum += x;
    sum_sq += x * x;
  }
  // Mean 1/2 (sd of the mean 0.289/sqrt(n) = 6.5e-4), variance 1/12.
  EXPECT_NEAR(sum / n, 0.5, 0.003);
  EXPECT_NEAR(sum_sq / n - (sum / n) * (sum / n), 1.0 / 12.0, 0.002);
}

}  // namespace
}  // namespace calstand::sim

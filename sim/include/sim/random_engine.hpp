#pragma once

#include <bit>
#include <cstdint>
#include <limits>

namespace calstand::sim {

/// xoshiro256++ (Blackman and Vigna, "Scrambled linear pseudorandom number generators", 2021):
/// a 64-bit generator with 256 bits of state, period 2^256 - 1, that passes BigCrush.
///
/// Why not std::mt19937_64: the simulator owns one engine per noise source (so adding a source
/// never shifts another's numbers), up to a few dozen per IMU, and the Mersenne Twister's 2.5 KB
/// of state each made its batch refills a sixth of the whole simulation time. This engine's
/// state is 32 bytes and each number costs a handful of instructions.
/// Satisfies std::uniform_random_bit_generator.
class Xoshiro256pp {
 public:
  using result_type = std::uint64_t;

  /// Fills the state from a 64-bit seed with splitmix64, as the authors recommend (never all
  /// zero, and nearby seeds give unrelated states).
  explicit Xoshiro256pp(std::uint64_t seed = 1) {
    for (auto& word : s_) {
      seed += 0x9e3779b97f4a7c15ULL;
      std::uint64_t z = seed;
      z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
      word = z ^ (z >> 31U);
    }
  }

  /// An engine with exactly this state (not all zero), for checks against the algorithm.
  static Xoshiro256pp from_state(std::uint64_t a, std::uint64_t b, std::uint64_t c,
                                 std::uint64_t d) {
    Xoshiro256pp e;
    e.s_[0] = a;
    e.s_[1] = b;
    e.s_[2] = c;
    e.s_[3] = d;
    return e;
  }

  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }

  result_type operator()() {
    const std::uint64_t result = std::rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17U;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = std::rotl(s_[3], 45);
    return result;
  }

 private:
  std::uint64_t s_[4];
};

}  // namespace calstand::sim

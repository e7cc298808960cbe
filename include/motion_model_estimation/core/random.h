// Seeded random generators with platform-independent distributions (the std:: distributions'
// output is implementation-defined, which would break "same seed, same result" across builds).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace mme {

/// splitmix64's step (the golden-ratio increment) and its output mix: unrelated words from
/// neighbouring inputs, for seeding.
constexpr uint64_t kSplitMix64Step = 0x9e3779b97f4a7c15ULL;
inline uint64_t splitMix64Mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// xoshiro256** (Blackman and Vigna), its state filled by splitmix64 from one seed: cheap to
/// seed, so each child of a generation can have its own stream.
class Xoshiro256 {
 public:
  explicit Xoshiro256(uint64_t seed) {
    for (uint64_t& word : s_) {
      seed += kSplitMix64Step;
      word = splitMix64Mix(seed);
    }
  }
  uint64_t operator()() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

template <class Engine>
class BasicRandom {
 public:
  explicit BasicRandom(uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform integer in [0, n) (n > 0); the slight modulo bias is irrelevant here.
  int index(int n) { return static_cast<int>(engine_() % static_cast<uint64_t>(n)); }
  /// Standard normal (Box-Muller, no cached second value so the stream is easy to reason about).
  double normal() {
    const double u1 = (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  uint64_t next() { return engine_(); }

 private:
  Engine engine_;
};

/// The scenes' and data generators' stream (Mersenne Twister: their outputs are fixed by it).
using Random = BasicRandom<std::mt19937_64>;
/// The evolution strategy's per-child streams.
using FastRandom = BasicRandom<Xoshiro256>;

}  // namespace mme

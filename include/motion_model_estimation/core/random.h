// A seeded random generator with platform-independent distributions (the std:: distributions'
// output is implementation-defined, which would break "same seed, same result" across builds).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace mme {

class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
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
  std::mt19937_64 engine_;
};

}  // namespace mme

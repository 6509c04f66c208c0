// A small, portable, seeded generator: the same seed gives the same numbers with any
// compiler and standard library (std::uniform_real_distribution does not promise that).
#pragma once

#include <cstdint>
#include <string>

namespace floorpose {

// A stable hash of a text (FNV-1a): the same id gives the same seed on any machine.
uint64_t Fnv1a(const std::string& text);

// SplitMix64 (Steele, Lea, Flood 2014).
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Standard normal (Box-Muller).
  double Gaussian();

 private:
  uint64_t state_;
};

}  // namespace floorpose

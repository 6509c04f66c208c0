#include "core/select.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/random.h"

namespace floorpose {
namespace {

// NthSmallest against a sort, below and above the size where it takes the histogram,
// with ties, zeros, subnormals and values spread over many octaves.
TEST(NthSmallestTest, IsTheSortedSetsElement) {
  SplitMix64 rng(7);
  for (size_t n : {1u, 2u, 3u, 100u, 16383u, 16384u, 50001u, 200000u}) {
    std::vector<double> v(n);
    for (size_t i = 0; i < n; ++i) {
      const double u = rng.Uniform();
      if (u < 0.1) {
        v[i] = 0.0;
      } else if (u < 0.15) {
        v[i] = std::numeric_limits<double>::denorm_min() * static_cast<double>(i % 7);
      } else if (u < 0.4) {
        v[i] = 0.25;  // many ties
      } else {
        v[i] = std::abs(rng.Gaussian()) * std::pow(10.0, rng.Uniform(-6, 3));
      }
    }
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    for (size_t k : {size_t{0}, n / 4, n / 2, n - 1}) {
      std::vector<double> work = v;
      EXPECT_EQ(NthSmallest(work, k), sorted[k]) << "n " << n << " k " << k;
    }
  }
}

}  // namespace
}  // namespace floorpose

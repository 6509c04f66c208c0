// Order statistics of large sets without sorting them.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace floorpose {

// The k-th smallest (from 0) of non-negative numbers (no NaN), exactly what nth_element
// gives; reorders v, k < v.size(). A large set is first narrowed to one bucket of a
// histogram of its top 16 bits (a non-negative double's bits sort as it does): a
// nth_element over a set beyond the cache costs several passes, the histogram two.
inline double NthSmallest(std::vector<double>& v, size_t k) {
  constexpr size_t kHistogramFrom = size_t{1} << 14;
  if (v.size() < kHistogramFrom) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  auto top = [](double x) {
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    return static_cast<uint32_t>(bits >> 48);
  };
  thread_local std::vector<uint32_t> histogram;  // 256 KB, kept for the thread's next call
  histogram.assign(size_t{1} << 16, 0);
  for (double x : v) ++histogram[top(x)];
  size_t below = 0;
  uint32_t bucket = 0;
  while (below + histogram[bucket] <= k) below += histogram[bucket++];
  size_t n = 0;
  for (double x : v)
    if (top(x) == bucket) v[n++] = x;
  const auto at = static_cast<std::ptrdiff_t>(k - below);
  std::nth_element(v.begin(), v.begin() + at, v.begin() + static_cast<std::ptrdiff_t>(n));
  return v[k - below];
}

}  // namespace floorpose

#include "core/random.h"

#include <cmath>

namespace floorpose {

double SplitMix64::Gaussian() {
  double u1 = Uniform();
  while (u1 <= 0.0) u1 = Uniform();
  const double u2 = Uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace floorpose

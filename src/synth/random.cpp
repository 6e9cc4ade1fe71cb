#include "random.h"

#include <cmath>

namespace dynahand::synth::detail {
namespace {

constexpr int kBins = 4096;

// Inverse of the standard normal CDF by Newton's method on erfc (double precision).
double inverseNormalCdf(double p) {
  double x = 0.0;
  for (int i = 0; i < 60; ++i) {
    const double cdf = 0.5 * std::erfc(-x / std::sqrt(2.0));
    const double pdf = std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
    const double step = (cdf - p) / pdf;
    x -= step;
    if (std::fabs(step) < 1e-12) break;
  }
  return x;
}

std::array<float, kBins> makeTable() {
  std::array<double, kBins> values{};
  double sumSq = 0.0;
  for (int i = 0; i < kBins; ++i) {
    values[static_cast<std::size_t>(i)] = inverseNormalCdf((i + 0.5) / kBins);
    sumSq += values[static_cast<std::size_t>(i)] * values[static_cast<std::size_t>(i)];
  }
  // The table is symmetric (mean 0); rescale so its variance is exactly 1.
  const double scale = 1.0 / std::sqrt(sumSq / kBins);
  std::array<float, kBins> table{};
  for (int i = 0; i < kBins; ++i)
    table[static_cast<std::size_t>(i)] =
        static_cast<float>(values[static_cast<std::size_t>(i)] * scale);
  return table;
}

}  // namespace

float normal(std::uint64_t r) {
  static const std::array<float, kBins> kTable = makeTable();
  return kTable[static_cast<std::size_t>(r >> 52)];
}

}  // namespace dynahand::synth::detail

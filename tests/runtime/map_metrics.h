// How close one light map is to another, as the accuracy bars state it: relative RMSE over every
// texel and channel (sqrt(sum (g - w)^2 / sum w^2)), and the ratio got / want over the values
// that matter (want >= 1 % of its own 99th percentile, as the accuracy verb counts them): its
// median (the signed bias) and its 1st percentile.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace lightpatch::testing {

struct MapMetrics {
  double relative_rmse = 0.0;
  double median_ratio = 1.0;
  double p1_ratio = 1.0;
  double min_value = 0.0;  // smallest value of `got`
  size_t counted = 0;      // values in the ratio statistics
};

// `got` and `want` hold the same number of values (any channel layout, the same in both).
template <typename G, typename W>
MapMetrics compare_maps(const G* got, const W* want, size_t n) {
  MapMetrics m;
  double err = 0.0, ref = 0.0;
  std::vector<double> sorted;
  sorted.reserve(n);
  m.min_value = n ? double(got[0]) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double g = double(got[i]), w = double(want[i]);
    err += (g - w) * (g - w);
    ref += w * w;
    sorted.push_back(w);
    m.min_value = std::min(m.min_value, g);
  }
  m.relative_rmse = ref > 0.0 ? std::sqrt(err / ref) : std::sqrt(err);
  if (n == 0) return m;
  std::sort(sorted.begin(), sorted.end());
  const double floor = 0.01 * sorted[size_t(0.99 * double(n - 1))];
  std::vector<double> ratios;
  for (size_t i = 0; i < n; ++i) {
    const double w = double(want[i]);
    if (w > 0.0 && w >= floor) ratios.push_back(double(got[i]) / w);
  }
  m.counted = ratios.size();
  if (ratios.empty()) return m;
  std::sort(ratios.begin(), ratios.end());
  m.median_ratio = ratios[ratios.size() / 2];
  m.p1_ratio = ratios[size_t(0.01 * double(ratios.size() - 1))];
  return m;
}

}  // namespace lightpatch::testing

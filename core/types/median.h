#pragma once
// The median of a sample (the upper one of an even count), 0 for none.
#include <algorithm>
#include <vector>

namespace bathyslam {

inline double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace bathyslam

#pragma once
// Navigation at any time inside its span: position linearly, attitude by slerp.
#include <optional>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam {

// The navigation at `time`, or nothing when `time` lies outside [front().time, back().time].
// `nav` must be time-ordered (the bundle reader guarantees it).
std::optional<NavSample> interpolate_nav(const std::vector<NavSample>& nav, double time);

}  // namespace bathyslam

#pragma once
// Survey lines: the straight legs of a trajectory (lawnmower lines, check lines), found by
// splitting the navigation where the course turns.
#include <cstddef>
#include <vector>

#include "core/types/survey.h"

namespace bathyslam {

struct LineConfig {
  double course_window_m = 10.0;   // course measured over this distance behind and ahead
  double max_turn_deg = 5.0;       // a sample whose course changes more is in a turn
  double max_course_spread_deg = 20.0;  // a line's samples stay this close to its course
  double min_length_m = 30.0;      // shorter straight stretches are not lines
};

struct SurveyLine {
  std::size_t first = 0;  // index of the first navigation sample on the line
  std::size_t last = 0;   // index of the last one (inclusive)
  double course_deg = 0;  // course over ground from first to last, clockwise from north
  double length_m = 0;    // distance along the line
};

std::vector<SurveyLine> split_lines(const std::vector<NavSample>& nav, const LineConfig& config = {});

}  // namespace bathyslam

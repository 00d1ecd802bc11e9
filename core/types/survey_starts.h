#pragma once
// Several surveys of one site in one graph (issue 33): their submaps (the graph's nodes) numbered
// on across the surveys, and `starts` the first node of each survey after the first, ascending
// (SubmapSet::survey_starts, GraphConfig::survey_starts). Empty: one survey.
#include <algorithm>
#include <vector>

namespace bathyslam {

// The survey (0-based, in join order) that node `node` belongs to.
inline int survey_of(const std::vector<int>& starts, int node) {
  return static_cast<int>(std::upper_bound(starts.begin(), starts.end(), node) - starts.begin());
}

// The nodes [begin, end) of survey `survey` among `nodes` in all.
struct NodeRange {
  int begin = 0, end = 0;
  int size() const { return end - begin; }
};
inline NodeRange survey_nodes(const std::vector<int>& starts, int survey, int nodes) {
  return {survey > 0 ? starts.at(survey - 1) : 0, survey < static_cast<int>(starts.size()) ? starts[survey] : nodes};
}

}  // namespace bathyslam

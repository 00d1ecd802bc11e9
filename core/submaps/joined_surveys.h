#pragma once
// Several surveys of one site as one set of submaps for one graph (issue 33): each survey keeps
// its own dead-reckoning chain, and GraphConfig::survey_starts (from SubmapSet::survey_starts)
// hangs each later survey off the first one's start by both start fixes.
#include <vector>

#include "core/submaps/submap.h"
#include "core/types/survey_starts.h"

namespace bathyslam {

// The surveys' submaps in the order given, in the first survey's map frame (each later one's
// poses moved from its own local origin to the first's; soundings stay in their submap frames),
// their lines numbered on (a survey's lines keep their navigation indices, which are its own),
// and the footprint of the coarsest, whose lengths serve all of them. Throws
// std::invalid_argument for no surveys or a survey without submaps, naming it by its position.
SubmapSet join_surveys(std::vector<SubmapSet> surveys);

// The survey (0-based, in join order) that submap `index` belongs to.
int survey_of_submap(const SubmapSet& set, int index);

// The submaps [begin, end) of survey `survey` (0-based, in join order).
NodeRange survey_submaps(const SubmapSet& set, int survey);

}  // namespace bathyslam

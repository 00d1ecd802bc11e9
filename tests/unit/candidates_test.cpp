#include "core/candidates/candidates.h"
#include "core/submaps/joined_surveys.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <unordered_set>

#include "tests/unit/true_submaps.h"

namespace bathyslam {
namespace {

const SubmapSet& true_submaps() {
  static const SubmapSet set = true_small_submaps(2);
  return set;
}

// The 1 m cells a submap's soundings fall in: the ground truth of where it overlaps another.
std::unordered_set<int64_t> cells_of(const Submap& s) {
  std::unordered_set<int64_t> cells;
  for (const Eigen::Vector3f& p : s.points) {
    const Eigen::Vector3d m = s.dr_pose * p.cast<double>();
    cells.insert((static_cast<int64_t>(std::floor(m.x())) << 32) ^ (static_cast<int64_t>(std::floor(m.y())) & 0xffffffff));
  }
  return cells;
}

double true_overlap_fraction(const std::unordered_set<int64_t>& a, const std::unordered_set<int64_t>& b) {
  std::size_t common = 0;
  for (int64_t c : a) common += b.count(c);
  return static_cast<double>(common) / static_cast<double>(std::min(a.size(), b.size()));
}

using PairSet = std::set<std::pair<int, int>>;

PairSet pair_set(const std::vector<CandidatePair>& pairs) {
  PairSet out;
  for (const CandidatePair& p : pairs) out.insert({p.target, p.source});
  return out;
}

TEST(Candidates, TheGridIndexFindsExactlyWhatComparingAllPairsFinds) {
  const SubmapSet& set = true_submaps();
  const auto poses = poses_of(set);
  const CandidateConfig config;
  PairSet brute_force;
  for (const Submap& a : set.submaps) {
    for (const Submap& b : set.submaps) {
      if (a.index >= b.index || !on_adjacent_lines(set, a.index, b.index, config)) continue;
      const Footprint fa = footprint_of(a, poses[a.index]), fb = footprint_of(b, poses[b.index]);
      if (overlap_area_m2(fa, fb) / std::min(fa.area_m2, fb.area_m2) >= config.min_overlap_fraction) {
        brute_force.insert({a.index, b.index});
      }
    }
  }
  ASSERT_GT(brute_force.size(), 10u);
  EXPECT_EQ(pair_set(adjacent_line_candidates(set, poses, config)), brute_force);
}

// A batch's search finds exactly the whole search's pairs whose later submap is in the batch.
TEST(Candidates, ABatchFindsTheWholeSearchsPairsEndingInIt) {
  const SubmapSet& set = true_submaps();
  const auto poses = poses_of(set);
  CandidateConfig config;
  config.loop_min_submap_gap = 2;
  const int n = static_cast<int>(set.submaps.size());
  const PairSet adjacent = pair_set(adjacent_line_candidates(set, poses, config));
  const PairSet loops = pair_set(loop_candidates(set, poses, config));
  ASSERT_GT(adjacent.size(), 10u);
  ASSERT_GT(loops.size(), 0u);
  PairSet adjacent_by_batch, loops_by_batch;
  for (int begin = 0; begin < n; begin += 7) {
    const LaterSubmaps batch{begin, std::min(n, begin + 7)};
    for (const CandidatePair& p : adjacent_line_candidates(set, poses, config, batch)) {
      EXPECT_TRUE(p.source >= batch.begin && p.source < batch.end);
      adjacent_by_batch.insert({p.target, p.source});
    }
    for (const CandidatePair& p : loop_candidates(set, poses, config, batch)) loops_by_batch.insert({p.target, p.source});
  }
  EXPECT_EQ(adjacent_by_batch, adjacent);
  EXPECT_EQ(loops_by_batch, loops);
}

// Against where the soundings really are: every pair of submaps on adjacent lines whose
// soundings share a good part of their cells is a candidate, and no candidate is a pair whose
// soundings share (next to) nothing.
// Two surveys of one site: their lines are numbered on (join_surveys), so the first survey's last
// lines and the second's first look like neighbours by number. A pair across the surveys is never
// an adjacent-line pair; it is a loop candidate however close their indices.
TEST(Candidates, PairsAcrossTwoSurveysAreLoopsNeverAdjacentLines) {
  SubmapSet set = true_submaps();
  const auto poses = poses_of(set);
  const CandidateConfig config;
  const PairSet one_survey = pair_set(adjacent_line_candidates(set, poses, config));
  // The second survey starts at the first submap of the middle line.
  int start = 0;
  const int middle = set.submaps[set.submaps.size() / 2].line;
  while (set.submaps[start].line != middle) ++start;
  set.survey_starts = {start};
  PairSet across;
  for (const auto& [a, b] : one_survey) {
    if (a < start && b >= start) across.insert({a, b});
  }
  ASSERT_GT(across.size(), 0u);
  for (const CandidatePair& p : adjacent_line_candidates(set, poses, config)) {
    EXPECT_EQ(survey_of_submap(set, p.target), survey_of_submap(set, p.source)) << p.target << "-" << p.source;
  }
  CandidateConfig every = config;
  every.max_pairs_per_other_survey = every.max_pairs_across_surveys = 100000;
  const std::vector<CandidatePair> all = loop_candidates(set, poses, every);
  const PairSet loops = pair_set(all);
  for (const auto& pair : across) EXPECT_TRUE(loops.contains(pair)) << pair.first << "-" << pair.second;

  // Capped: each later submap keeps the pairs with the other survey it overlaps most.
  std::map<int, std::vector<double>> overlaps;  // later submap -> its overlaps with the first survey
  for (const CandidatePair& p : all) {
    if (p.target < start && p.source >= start) overlaps[p.source].push_back(p.overlap_fraction);
  }
  std::map<int, std::vector<double>> kept;
  for (const CandidatePair& p : loop_candidates(set, poses, config)) {
    if (p.target < start && p.source >= start) kept[p.source].push_back(p.overlap_fraction);
  }
  ASSERT_EQ(kept.size(), overlaps.size());
  for (auto& [source, fractions] : overlaps) {
    std::sort(fractions.rbegin(), fractions.rend());
    fractions.resize(std::min<std::size_t>(fractions.size(), config.max_pairs_per_other_survey));
    std::sort(kept[source].rbegin(), kept[source].rend());
    EXPECT_EQ(kept[source], fractions) << "submap " << source;
  }

  // Three surveys, at most one pair of a later submap in all.
  int third = start;
  while (set.submaps[third].line < middle + 2) ++third;
  set.survey_starts = {start, third};
  CandidateConfig three = config;
  three.max_pairs_across_surveys = 1;
  std::map<int, std::map<int, int>> by_survey;  // later submap -> earlier survey -> pairs
  for (const CandidatePair& p : loop_candidates(set, poses, three)) {
    const int from = survey_of_submap(set, p.target);
    if (from != survey_of_submap(set, p.source)) ++by_survey[p.source][from];
  }
  ASSERT_FALSE(by_survey.empty());
  for (const auto& [source, pairs] : by_survey) {
    int total = 0;
    for (const auto& [survey, count] : pairs) {
      EXPECT_LE(count, three.max_pairs_per_other_survey) << "submap " << source << ", survey " << survey;
      total += count;
    }
    EXPECT_LE(total, three.max_pairs_across_surveys) << "submap " << source;
  }
  set.survey_starts = {start};

  // None: each survey alone, the pairs within the surveys all kept.
  CandidateConfig apart = config;
  apart.max_pairs_per_other_survey = 0;
  const std::vector<CandidatePair> alone = loop_candidates(set, poses, apart);
  for (const CandidatePair& p : alone) EXPECT_EQ(survey_of_submap(set, p.target), survey_of_submap(set, p.source));
  EXPECT_EQ(alone.size(), all.size() - std::count_if(all.begin(), all.end(), [&](const CandidatePair& p) {
                                         return p.target < start && p.source >= start;
                                       }));
}

TEST(Candidates, FindEveryTrulyOverlappingAdjacentLinePairAndNoOther) {
  const SubmapSet& set = true_submaps();
  const CandidateConfig config;
  const PairSet found = pair_set(adjacent_line_candidates(set, poses_of(set), config));
  std::vector<std::unordered_set<int64_t>> cells;
  for (const Submap& s : set.submaps) cells.push_back(cells_of(s));

  int truly_overlapping = 0;
  for (const Submap& a : set.submaps) {
    for (const Submap& b : set.submaps) {
      if (a.index >= b.index || !on_adjacent_lines(set, a.index, b.index, config)) continue;
      const double fraction = true_overlap_fraction(cells[a.index], cells[b.index]);
      const bool is_candidate = found.count({a.index, b.index}) > 0;
      // Footprints are rectangles around the soundings, so the margins allow for their corners.
      if (fraction >= config.min_overlap_fraction + 0.05) {
        ++truly_overlapping;
        EXPECT_TRUE(is_candidate) << a.index << "-" << b.index << " share " << fraction << " of their cells";
      }
      if (is_candidate) {
        EXPECT_GT(fraction, 0.02) << a.index << "-" << b.index << " share nothing";
      }
    }
  }
  EXPECT_GT(truly_overlapping, 10);
}

TEST(Candidates, SubmapsOnNonAdjacentOrCrossingLinesAreNotPaired) {
  const SubmapSet& set = true_submaps();
  const CandidateConfig config;
  for (const CandidatePair& p : adjacent_line_candidates(set, poses_of(set), config)) {
    const int la = set.submaps[p.target].line, lb = set.submaps[p.source].line;
    EXPECT_NE(la, lb);
    EXPECT_LE(std::abs(la - lb), config.k_adjacent_lines);
    double d = std::fmod(std::abs(set.lines[la].course_deg - set.lines[lb].course_deg), 180.0);
    EXPECT_LE(std::min(d, 180.0 - d), config.parallel_tolerance_deg);
  }
}

}  // namespace
}  // namespace bathyslam

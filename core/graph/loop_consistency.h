#pragma once
// loop_consistency: which loop closures to believe. Each must be one DR could have come to
// (dr_noise.h), and together they must agree with one another: pairwise consistency
// maximisation (PCM, Mangelson et al., ICRA 2018) keeps the largest set of loops every two of
// which close a cycle through dead reckoning.
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "core/graph/dr_noise.h"
#include "core/graph/pose_graph.h"
#include "core/types/fields.h"

namespace bathyslam {

// A loop closure: `measured` is the pose of `to` in `from`'s level frame, `covariance` its
// error's in dr_noise.h's parametrisation.
struct LoopCandidate {
  int from = 0;
  int to = 0;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  Covariance6 covariance = Covariance6::Identity();
  int id = -1;  // the caller's stable name for this loop, for KnownConflicts; -1: none
};

// A registration edge as a loop candidate, its frames levelled at the nodes' DR poses and its
// covariance from its information (measurement_covariance).
LoopCandidate loop_candidate(const PoseGraphEdge& edge, const std::vector<Eigen::Isometry3d>& dead_reckoning);

// Squared Mahalanobis distance (x, y, yaw) from identity of the cycle loop i closes with loop j:
// a →(i) b →(DR) d →(j⁻¹) c →(DR) a, under the first-order covariance of both measurements and
// both DR chains. The two chains are taken as independent. For loops running forward in time
// (from < to; select_consistent_loops turns the others round) chains can share steps only
// traversed in opposite directions, whose errors cancel, so the covariance is then too large
// and the test errs towards calling loops consistent.
double pair_mahalanobis2(const LoopCandidate& i, const LoopCandidate& j, const DrNoiseModel& dr);

// The pairs of named loops that disagree (pair_mahalanobis2 beyond a threshold), each pair
// tested once: a registration's measurement and dead reckoning do not change once made, so a
// survey registered batch by batch, which selects again after each batch, tests a new loop
// against the loops before it and never again (`large`: ~5,500 loops; testing and scanning every
// pair each batch grew with the cube of the survey, docs/performance.md). Only the few
// disagreeing pairs are kept. For one DrNoiseModel, one threshold and one set of named loops,
// each given forward (from <= to) and always the same under its id: a new noise model needs a
// new KnownConflicts, whose tests then cost n²/2 again.
class KnownConflicts {
 public:
  // The disagreeing pairs among `loops`, as index pairs {a, b}, a < b, into `loops`. Throws
  // invalid_argument for a loop without an id or an id given twice.
  std::vector<std::pair<int, int>> among(const std::vector<LoopCandidate>& loops, const DrNoiseModel& dr,
                                         double pair_chi2_threshold);

 private:
  int slot(const LoopCandidate& loop, const DrNoiseModel& dr, double pair_chi2_threshold);
  std::vector<int> slot_of_id_;               // -1: no slot yet
  std::vector<LoopCandidate> loops_;          // by slot
  std::vector<std::vector<int>> conflicts_;   // by slot: the earlier slots it disagrees with
};

// `loop` as the same measurement from `to` to `from`.
LoopCandidate reversed(const LoopCandidate& loop);

using Adjacency = std::vector<std::vector<char>>;  // symmetric, [i][j] != 0: an edge

struct Clique {
  std::vector<int> members;  // ascending
  bool exact = true;         // false: the greedy heuristic's, or the search ran out of steps
};

// The largest clique: branch and bound with a colouring bound (Tomita's MCQ) for up to
// `max_exact_vertices` vertices and `max_steps` branches; otherwise, or when the steps run out,
// the best a greedy search found (from each vertex, repeatedly add the candidate of highest
// degree that is adjacent to every member so far).
Clique maximum_clique(const Adjacency& adjacency, int max_exact_vertices = 300, long max_steps = 2'000'000);

// The largest clique of the graph on `n` vertices whose every pair is an edge but `missing`
// (index pairs): the union of maximum_clique over the groups the missing edges join, since two
// vertices of different groups are always adjacent. Exact wherever each group is small enough
// for maximum_clique's search (and its branch budget, which applies to each group), however many
// vertices; costs O(n + missing) beside the groups' own searches, O(m²) and more for m members.
// One loop that disagrees with many joins them all into one group.
Clique maximum_clique_missing(int n, const std::vector<std::pair<int, int>>& missing, int max_exact_vertices = 300,
                              long max_steps = 2'000'000);

struct LoopConsistencyConfig {
  PlausibilityConfig plausibility;
  // χ²₃ at 99.9 %, as for plausibility: a correct pair is called inconsistent once in a thousand,
  // and one such refusal only costs a loop if its other partners cannot carry it into the clique.
  double pair_chi2_threshold = 16.27;
  // Exact search in each group of loops their disagreements join (maximum_clique_missing) up to
  // this many loops (a few seconds at worst on a dense graph), greedy above; both also bounded
  // by a branch budget.
  int max_exact_loops = 300;
  long max_branch_steps = 2'000'000;
  template <typename Field>
  void fields(Field&& field) {
    nested("plausibility", plausibility, field);
    field("pair_chi2_threshold", pair_chi2_threshold, 0.01, 1e6);
    field("max_exact_loops", max_exact_loops, 0, 100000);
    field("max_branch_steps", max_branch_steps, 0, 1e12);
  }
};

enum class LoopVerdict {
  kept,
  implausible,   // refused by DR alone (plausibility)
  inconsistent,  // plausible, but not in the largest consistent set
};

struct LoopSelection {
  std::vector<LoopVerdict> verdicts;   // per candidate, in input order
  std::vector<double> dr_mahalanobis2; // per candidate: its plausibility distance
  std::vector<int> kept;               // candidates kept, ascending
  bool exact = true;                   // the clique is proven largest
};

// Plausibility against DR for each loop, then the largest pairwise-consistent set of the
// plausible ones. A lone plausible loop is kept: there is nothing to check it against, and DR
// has already found it possible. Several plausible loops of which no two agree keep none:
// each is contradicted and none confirmed.
// With `known`, the pairs' tests come from it (and go into it); every plausible loop must then
// be named (KnownConflicts::among throws otherwise).
LoopSelection select_consistent_loops(const std::vector<LoopCandidate>& loops, const DrNoiseModel& dr,
                                      const LoopConsistencyConfig& config = {}, KnownConflicts* known = nullptr);

}  // namespace bathyslam

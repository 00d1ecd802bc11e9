#include "core/graph/loop_consistency.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace bathyslam {
namespace {

struct UncertainPose {
  Eigen::Isometry3d pose;
  Covariance6 covariance;  // in the pose's `from` frame
};

// First-order covariance of a product of relative poses, in its first frame. A factor's error
// (δt, δθ in its own first frame) reaches the product's end turned into the first frame by R_P
// (the factor's start there), and its δθ also swings everything after the factor about the
// factor's end: the end moves by δθ × (t_end_of_product − t_end_of_factor).
UncertainPose compose(const std::vector<UncertainPose>& factors) {
  std::vector<Eigen::Isometry3d> starts = {Eigen::Isometry3d::Identity()};
  for (const UncertainPose& f : factors) starts.push_back(starts.back() * f.pose);
  const Eigen::Vector3d end = starts.back().translation();
  Covariance6 covariance = Covariance6::Zero();
  for (std::size_t k = 0; k < factors.size(); ++k) {
    Covariance6 jacobian = Covariance6::Zero();
    jacobian.topLeftCorner<3, 3>() = starts[k].linear();
    jacobian.bottomRightCorner<3, 3>() = starts[k].linear();
    jacobian.topRightCorner<3, 3>() = -skew(end - starts[k + 1].translation()) * starts[k].linear();
    covariance += jacobian * factors[k].covariance * jacobian.transpose();
  }
  return {starts.back(), covariance};
}

// The graph for the greedy search: vertices renumbered by degree, highest first (ties in index
// order), each one's neighbours as a row of bits. "The candidate of highest degree" is then the
// lowest set bit of the candidates, and every candidate left after it lies above it: a step is a
// scan and an AND over the words from there on. Three surveys' ~3,000 loop candidates made the
// greedy search over vectors of ints most of a site job's time (docs/sites.md).
struct DegreeOrderedGraph {
  DegreeOrderedGraph(const Adjacency& adjacency, const std::vector<int>& degree)
      : old_of(adjacency.size()), new_of(adjacency.size()), words((adjacency.size() + 63) / 64) {
    std::iota(old_of.begin(), old_of.end(), 0);
    std::stable_sort(old_of.begin(), old_of.end(), [&](int a, int b) { return degree[a] > degree[b]; });
    for (std::size_t k = 0; k < old_of.size(); ++k) new_of[old_of[k]] = static_cast<int>(k);
    rows.assign(old_of.size(), std::vector<uint64_t>(words, 0));
    for (std::size_t k = 0; k < old_of.size(); ++k) {
      for (std::size_t u = 0; u < old_of.size(); ++u) {
        if (adjacency[old_of[k]][u] && u != static_cast<std::size_t>(old_of[k])) rows[k][new_of[u] / 64] |= uint64_t{1} << (new_of[u] % 64);
      }
    }
  }
  std::vector<int> old_of, new_of;
  std::size_t words;
  std::vector<std::vector<uint64_t>> rows;
};

// A start of the greedy search: from `seed`, add the candidate of highest degree adjacent to
// all members so far, until none is left. Members in the original numbering.
std::vector<int> greedy_clique_from(int seed, const DegreeOrderedGraph& graph) {
  std::vector<int> clique = {seed};
  std::vector<uint64_t> candidates = graph.rows[graph.new_of[seed]];
  std::size_t word = 0;
  for (;;) {
    while (word < graph.words && candidates[word] == 0) ++word;
    if (word == graph.words) break;
    const int next = static_cast<int>(word * 64) + std::countr_zero(candidates[word]);
    clique.push_back(graph.old_of[next]);
    const std::vector<uint64_t>& row = graph.rows[next];
    for (std::size_t w = word; w < graph.words; ++w) candidates[w] &= row[w];
  }
  return clique;
}

std::vector<int> greedy_clique(const Adjacency& adjacency, const std::vector<int>& degree) {
  const DegreeOrderedGraph graph(adjacency, degree);
  std::vector<int> best;
  for (int seed = 0; seed < static_cast<int>(adjacency.size()); ++seed) {
    if (degree[seed] + 1 <= static_cast<int>(best.size())) continue;  // cannot beat it
    std::vector<int> clique = greedy_clique_from(seed, graph);
    if (clique.size() > best.size()) best = std::move(clique);
  }
  return best;
}

// Tomita and Seki's MCQ: colour the candidates greedily (no two neighbours share a colour), so a
// clique among the first k of them in colour order has at most colour(k) members; branch on the
// last first and prune as soon as the bound cannot beat the best.
class CliqueSearch {
 public:
  CliqueSearch(const Adjacency& adjacency, std::vector<int> best, long max_steps)
      : adjacency_(adjacency), best_(std::move(best)), max_steps_(max_steps) {}

  void expand(const std::vector<int>& candidates) {
    if (++steps_ > max_steps_) {
      out_of_steps_ = true;
      return;
    }
    std::vector<int> order, bound;
    colour(candidates, order, bound);
    for (int k = static_cast<int>(order.size()) - 1; k >= 0 && !out_of_steps_; --k) {
      if (current_.size() + bound[k] <= best_.size()) return;
      const int v = order[k];
      current_.push_back(v);
      std::vector<int> next;
      for (int i = 0; i < k; ++i) {
        if (adjacency_[v][order[i]]) next.push_back(order[i]);
      }
      if (next.empty()) {
        if (current_.size() > best_.size()) best_ = current_;
      } else {
        expand(next);
      }
      current_.pop_back();
    }
  }

  const std::vector<int>& best() const { return best_; }
  bool out_of_steps() const { return out_of_steps_; }

 private:
  // `order`: the candidates by colour; bound[k]: the colour (1-based) of order[k].
  void colour(const std::vector<int>& candidates, std::vector<int>& order, std::vector<int>& bound) const {
    std::vector<std::vector<int>> classes;
    for (int v : candidates) {
      auto fits = [&](const std::vector<int>& c) {
        return std::none_of(c.begin(), c.end(), [&](int u) { return adjacency_[v][u]; });
      };
      auto it = std::find_if(classes.begin(), classes.end(), fits);
      if (it == classes.end()) {
        classes.emplace_back();
        it = classes.end() - 1;
      }
      it->push_back(v);
    }
    for (std::size_t c = 0; c < classes.size(); ++c) {
      for (int v : classes[c]) {
        order.push_back(v);
        bound.push_back(static_cast<int>(c) + 1);
      }
    }
  }

  const Adjacency& adjacency_;
  std::vector<int> best_, current_;
  long max_steps_;
  long steps_ = 0;
  bool out_of_steps_ = false;
};

}  // namespace

LoopCandidate loop_candidate(const PoseGraphEdge& edge, const std::vector<Eigen::Isometry3d>& dead_reckoning) {
  const Eigen::Isometry3d& from_pose = dead_reckoning.at(edge.from);
  const Eigen::Isometry3d& to_pose = dead_reckoning.at(edge.to);
  return {edge.from, edge.to, between_level_frames(edge.measured, from_pose, to_pose),
          measurement_covariance(edge, from_pose)};
}

// X⁻¹ = (Rᵀ, −Rᵀt); perturbing X by (δt, δθ) perturbs X⁻¹ by −(Rᵀδt + Rᵀ[t]ₓδθ, Rᵀδθ).
LoopCandidate reversed(const LoopCandidate& loop) {
  const Eigen::Matrix3d r_t = loop.measured.linear().transpose();
  Covariance6 jacobian = Covariance6::Zero();
  jacobian.topLeftCorner<3, 3>() = r_t;
  jacobian.topRightCorner<3, 3>() = r_t * skew(loop.measured.translation());
  jacobian.bottomRightCorner<3, 3>() = r_t;
  return {loop.to, loop.from, loop.measured.inverse(), jacobian * loop.covariance * jacobian.transpose(), loop.id};
}

double pair_mahalanobis2(const LoopCandidate& i, const LoopCandidate& j, const DrNoiseModel& dr) {
  const LoopCandidate j_back = reversed(j);
  const UncertainPose cycle = compose({{i.measured, i.covariance},
                                       {dr.relative_pose(i.to, j.to), dr.covariance(i.to, j.to)},
                                       {j_back.measured, j_back.covariance},
                                       {dr.relative_pose(j.from, i.from), dr.covariance(j.from, i.from)}});
  return mahalanobis2_xy_yaw(pose_difference(cycle.pose, Eigen::Isometry3d::Identity()), cycle.covariance);
}

int KnownConflicts::slot(const LoopCandidate& loop, const DrNoiseModel& dr, double pair_chi2_threshold) {
  if (loop.id >= static_cast<int>(slot_of_id_.size())) slot_of_id_.resize(loop.id + 1, -1);
  int& slot = slot_of_id_[loop.id];
  if (slot >= 0) return slot;
  slot = static_cast<int>(loops_.size());
  std::vector<int> conflicts;
  for (int earlier = 0; earlier < slot; ++earlier) {
    if (pair_mahalanobis2(loops_[earlier], loop, dr) > pair_chi2_threshold) conflicts.push_back(earlier);
  }
  loops_.push_back(loop);
  conflicts_.push_back(std::move(conflicts));
  return slot;
}

std::vector<std::pair<int, int>> KnownConflicts::among(const std::vector<LoopCandidate>& loops, const DrNoiseModel& dr,
                                                       double pair_chi2_threshold) {
  std::vector<int> slots;
  for (const LoopCandidate& loop : loops) {
    if (loop.id < 0) throw std::invalid_argument("KnownConflicts: a loop without an id");
    slots.push_back(slot(loop, dr, pair_chi2_threshold));
  }
  std::vector<int> index_of_slot(loops_.size(), -1);  // -1: not among `loops`
  for (std::size_t k = 0; k < slots.size(); ++k) {
    if (index_of_slot[slots[k]] >= 0) throw std::invalid_argument("KnownConflicts: loop id given twice");
    index_of_slot[slots[k]] = static_cast<int>(k);
  }
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t k = 0; k < slots.size(); ++k) {
    for (int earlier : conflicts_[slots[k]]) {
      const int other = index_of_slot[earlier];
      const int self = static_cast<int>(k);
      if (other >= 0) pairs.emplace_back(std::min(other, self), std::max(other, self));
    }
  }
  return pairs;
}

Clique maximum_clique(const Adjacency& adjacency, int max_exact_vertices, long max_steps) {
  const int n = static_cast<int>(adjacency.size());
  std::vector<int> degree(n, 0);
  for (int v = 0; v < n; ++v) {
    for (int u = 0; u < n; ++u) degree[v] += (u != v && adjacency[v][u]);
  }
  Clique clique;
  clique.members = greedy_clique(adjacency, degree);
  clique.exact = n <= max_exact_vertices;
  if (clique.exact && n > 0) {
    std::vector<int> all(n);
    std::iota(all.begin(), all.end(), 0);
    std::stable_sort(all.begin(), all.end(), [&](int a, int b) { return degree[a] > degree[b]; });
    CliqueSearch search(adjacency, clique.members, max_steps);
    search.expand(all);
    clique.members = search.best();
    clique.exact = !search.out_of_steps();
  }
  std::sort(clique.members.begin(), clique.members.end());
  return clique;
}

Clique maximum_clique_missing(int n, const std::vector<std::pair<int, int>>& missing, int max_exact_vertices,
                              long max_steps) {
  std::vector<int> parent(n);  // union-find over the missing edges
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& [a, b] : missing) parent[root(a)] = root(b);
  std::vector<std::vector<int>> group(n);  // by root: its vertices, ascending
  std::vector<int> place(n);               // a vertex's place in its group
  for (int v = 0; v < n; ++v) {
    std::vector<int>& g = group[root(v)];
    place[v] = static_cast<int>(g.size());
    g.push_back(v);
  }
  std::vector<std::vector<std::pair<int, int>>> missing_in(n);  // by root
  for (const auto& [a, b] : missing) missing_in[root(a)].emplace_back(place[a], place[b]);

  Clique clique;
  for (int r = 0; r < n; ++r) {
    const std::vector<int>& vertices = group[r];
    if (vertices.size() == 1) clique.members.push_back(vertices[0]);
    if (vertices.size() <= 1) continue;
    const std::size_t m = vertices.size();
    Adjacency adjacency(m, std::vector<char>(m, 1));
    for (std::size_t k = 0; k < m; ++k) adjacency[k][k] = 0;
    for (const auto& [a, b] : missing_in[r]) adjacency[a][b] = adjacency[b][a] = 0;
    const Clique part = maximum_clique(adjacency, max_exact_vertices, max_steps);
    for (int v : part.members) clique.members.push_back(vertices[v]);
    clique.exact = clique.exact && part.exact;
  }
  std::sort(clique.members.begin(), clique.members.end());
  return clique;
}

LoopSelection select_consistent_loops(const std::vector<LoopCandidate>& loops, const DrNoiseModel& dr,
                                      const LoopConsistencyConfig& config, KnownConflicts* known) {
  LoopSelection selection;
  selection.verdicts.assign(loops.size(), LoopVerdict::implausible);
  selection.dr_mahalanobis2.assign(loops.size(), 0.0);
  std::vector<LoopCandidate> forward;  // the plausible ones, from < to
  std::vector<int> index;              // their places in `loops`
  for (std::size_t k = 0; k < loops.size(); ++k) {
    const LoopCandidate loop = loops[k].from <= loops[k].to ? loops[k] : reversed(loops[k]);
    const PlausibilityTest test =
        plausibility(loop.measured, dr.relative_pose(loop.from, loop.to),
                     dr.covariance(loop.from, loop.to) + loop.covariance, config.plausibility.chi2_threshold);
    selection.dr_mahalanobis2[k] = test.mahalanobis2;
    if (!test.plausible) continue;
    selection.verdicts[k] = LoopVerdict::inconsistent;
    forward.push_back(loop);
    index.push_back(static_cast<int>(k));
  }

  const int n = static_cast<int>(forward.size());
  std::vector<std::pair<int, int>> disagreeing;
  if (known) {
    disagreeing = known->among(forward, dr, config.pair_chi2_threshold);
  } else {
    for (int a = 0; a < n; ++a) {
      for (int b = a + 1; b < n; ++b) {
        if (pair_mahalanobis2(forward[a], forward[b], dr) > config.pair_chi2_threshold) disagreeing.emplace_back(a, b);
      }
    }
  }
  const Clique clique = maximum_clique_missing(n, disagreeing, config.max_exact_loops, config.max_branch_steps);
  selection.exact = clique.exact;
  if (clique.members.size() >= 2 || n == 1) {
    for (int member : clique.members) {
      selection.verdicts[index[member]] = LoopVerdict::kept;
      selection.kept.push_back(index[member]);
    }
  }
  std::sort(selection.kept.begin(), selection.kept.end());
  return selection;
}

}  // namespace bathyslam

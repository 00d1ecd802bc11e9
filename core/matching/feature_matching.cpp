#include "core/matching/feature_matching.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/search/flann_tree.h"

namespace bathyslam {
namespace {

struct BestMatch {
  int index = -1;
  double mse = std::numeric_limits<double>::infinity();
};

// A descriptor split as a lower bound of descriptor_mse needs it: `coarse` is its projection on
// the functions constant over 4 x 4 blocks of the d x d samples (each block's sum over the square
// root of its size), `fine_norm` the length of the rest. The two parts are orthogonal, so
// |a - b|^2 >= |coarse_a - coarse_b|^2 + (fine_norm_a - fine_norm_b)^2: the elevation patches
// are smooth, most of a difference lies in the blocks, and most neighbours within the gate are
// ruled out by sixteen numbers instead of d^2.
struct DescriptorSummary {
  Eigen::Matrix<double, 16, 1> coarse = Eigen::Matrix<double, 16, 1>::Zero();
  double fine_norm = 0;
};

DescriptorSummary summary_of(const Eigen::VectorXf& descriptor) {
  // Row-major d x d samples (tsd_keypoints.cpp); any other layout only loosens the bound.
  const auto d = static_cast<int>(std::lround(std::sqrt(static_cast<double>(descriptor.size()))));
  DescriptorSummary s;
  std::array<double, 16> count{};
  const float* sample = descriptor.data();
  for (int r = 0; r < d; ++r) {
    const int block_row = std::min(3, r * 4 / d) * 4;
    for (int c = 0; c < d; ++c, ++sample) {
      const int block = block_row + std::min(3, c * 4 / d);
      s.coarse[block] += *sample;
      count[block] += 1;
    }
  }
  for (int b = 0; b < 16; ++b) s.coarse[b] = count[b] > 0 ? s.coarse[b] / std::sqrt(count[b]) : 0.0;
  s.fine_norm = std::sqrt(std::max(0.0, descriptor.cast<double>().squaredNorm() - s.coarse.squaredNorm()));
  return s;
}

double mse_lower_bound(const DescriptorSummary& a, const DescriptorSummary& b, Eigen::Index size) {
  const double fine_gap = a.fine_norm - b.fine_norm;
  return ((a.coarse - b.coarse).squaredNorm() + fine_gap * fine_gap) / static_cast<double>(size);
}

// One side of the pair: where its keypoints sit in the target frame and their descriptors.
struct Side {
  const std::vector<Keypoint>& keypoints;
  std::vector<Eigen::Vector3d> positions;
  std::vector<CentredDescriptor> descriptors;  // centred once for both directions
  std::vector<DescriptorSummary> summaries;
};

Side side_of(const std::vector<Keypoint>& keypoints) {
  Side side{keypoints, {}, {}, {}};
  side.positions.reserve(keypoints.size());
  side.descriptors.reserve(keypoints.size());
  side.summaries.reserve(keypoints.size());
  for (const Keypoint& k : keypoints) {
    side.positions.push_back(k.position);
    side.descriptors.push_back(centred(k.descriptor));
    side.summaries.push_back(summary_of(k.descriptor));
  }
  return side;
}

// For each query keypoint, its best match among the indexed keypoints within the gate, if it
// passes correlation and the ratio test.
std::vector<BestMatch> one_way(const Side& queries, const Side& indexed, const MatchConfig& config) {
  std::vector<BestMatch> best(queries.keypoints.size());
  if (indexed.keypoints.empty()) return best;
  // pcl::KdTreeFLANN<pcl::PointXY>'s tree and radius search, without its per-query OpenMP region.
  const FlannIndex tree = planar_index(indexed.positions);
  pcl::Indices near;
  std::vector<float> sq_distances;
  for (std::size_t i = 0; i < queries.keypoints.size(); ++i) {
    const float q[2] = {static_cast<float>(queries.positions[i].x()), static_cast<float>(queries.positions[i].y())};
    // In any order: the best and second-best MSE do not depend on it, and where two tie the
    // ratio test refuses the match whichever comes first (sorting was 5 % of `large`'s CPU).
    tree.within(q, config.max_distance_m, near, sq_distances, false);
    double second = std::numeric_limits<double>::infinity();
    const Eigen::Index size = queries.keypoints[i].descriptor.size();
    for (int j : near) {
      // A pair that cannot beat the second best changes nothing. The margin keeps rounding out:
      // descriptor_mse subtracts in float, up to ~1e-7 of the score below the exact difference.
      if (mse_lower_bound(queries.summaries[i], indexed.summaries[j], size) * (1 - 1e-6) >= second) continue;
      const double mse = descriptor_mse(queries.keypoints[i].descriptor, indexed.keypoints[j].descriptor, second);
      // Neither the best nor the second best can change (best <= second), so the costlier
      // correlation test need not run.
      if (mse >= second) continue;
      if (descriptor_ncc(queries.descriptors[i], indexed.descriptors[j]) < config.min_ncc) continue;
      if (mse < best[i].mse) {
        second = best[i].mse;
        best[i] = {j, mse};
      } else {
        second = std::min(second, mse);
      }
    }
    // A repetitive terrain offers two near-equal matches: trust neither.
    if (best[i].index >= 0 && !(best[i].mse < config.ratio * second)) best[i] = {};
  }
  return best;
}

}  // namespace

std::vector<FeatureMatch> match_features(const std::vector<Keypoint>& source, const std::vector<Keypoint>& target,
                                         const Eigen::Isometry3d& source_to_target, const MatchConfig& config) {
  Side source_side = side_of(source);
  for (Eigen::Vector3d& p : source_side.positions) p = source_to_target * p;
  const Side target_side = side_of(target);
  const std::vector<BestMatch> forward = one_way(source_side, target_side, config);
  const std::vector<BestMatch> backward = one_way(target_side, source_side, config);

  std::vector<FeatureMatch> matches;
  for (std::size_t i = 0; i < forward.size(); ++i) {
    const int j = forward[i].index;
    if (j >= 0 && backward[j].index == static_cast<int>(i)) matches.push_back({static_cast<int>(i), j, forward[i].mse});
  }
  // Mutual best matches are already one-to-one; sorting gives PROSAC its order.
  std::sort(matches.begin(), matches.end(), [](const FeatureMatch& a, const FeatureMatch& b) { return a.mse < b.mse; });
  return matches;
}

}  // namespace bathyslam

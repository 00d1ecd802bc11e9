#include "core/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <unordered_map>

#include <Eigen/Geometry>

#include "core/graph/pose_graph.h"
#include "core/types/survey_starts.h"

namespace bathyslam {

ErrorStats error_stats(std::vector<double> errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  std::sort(errors.begin(), errors.end());
  const double n = static_cast<double>(errors.size());
  double sum = 0, sum_sq = 0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  s.std = std::sqrt(std::max(0.0, sum_sq / n - s.mean * s.mean));
  auto percentile = [&](double p) { return errors[static_cast<std::size_t>(std::floor(p * (n - 1)))]; };
  s.p50 = percentile(0.50);
  s.p95 = percentile(0.95);
  s.p99 = percentile(0.99);
  s.max = errors.back();
  return s;
}

double quantile_upper_bound(const std::vector<double>& sorted, double p, double z) {
  if (sorted.empty()) return 0;
  const double n = static_cast<double>(sorted.size());
  const double rank = p * (n - 1) + z * std::sqrt(n * p * (1 - p));
  return sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(std::floor(rank)))];
}

namespace {

// Key: cell (20 bits each way, 1 m cells reach ±500 km) and line (up to 2^20 lines).
uint64_t cell_line_key(int64_t ix, int64_t iy, int line) {
  return (static_cast<uint64_t>(ix & 0xFFFFF) << 40) | (static_cast<uint64_t>(iy & 0xFFFFF) << 20) |
         static_cast<uint64_t>(line);
}

// Each line's mean elevation in each cell it has at least min_soundings in.
std::unordered_map<uint64_t, double> line_means(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                                const ConsistencyConfig& config) {
  struct Sum {
    double z = 0;
    int n = 0;
  };
  std::unordered_map<uint64_t, Sum> per_line_cell;
  for (const Submap& s : set.submaps) {
    if (s.line < 0) continue;
    const Eigen::Isometry3f pose = poses[s.index].cast<float>();
    for (const Eigen::Vector3f& p : s.points) {
      const Eigen::Vector3f m = pose * p;
      Sum& sum = per_line_cell[cell_line_key(static_cast<int64_t>(std::floor(m.x() / config.cell_m)),
                                             static_cast<int64_t>(std::floor(m.y() / config.cell_m)), s.line)];
      sum.z += m.z();
      ++sum.n;
    }
  }
  std::unordered_map<uint64_t, double> means;
  for (const auto& [k, sum] : per_line_cell) {
    if (sum.n >= config.min_soundings) means[k] = sum.z / sum.n;
  }
  return means;
}

struct Spread {
  double lo = INFINITY, hi = -INFINITY;
  int lines = 0;
  void add(double z) {
    lo = std::min(lo, z);
    hi = std::max(hi, z);
    ++lines;
  }
};

ConsistencyReport report_of(std::vector<double> errors, const ConsistencyConfig& config) {
  ConsistencyReport report;
  report.histogram.bin_width = config.histogram_bin_m;
  report.histogram.counts.assign(config.histogram_bins, 0);
  for (double e : errors) {
    const auto bin = std::min<std::size_t>(static_cast<std::size_t>(e / config.histogram_bin_m),
                                           config.histogram_bins - 1);
    ++report.histogram.counts[bin];
  }
  std::sort(errors.begin(), errors.end());
  report.p99_upper = quantile_upper_bound(errors, 0.99, 2.33);
  report.stats = error_stats(std::move(errors));
  return report;
}

// The centre (map frame) of the cell of a cell_line_key shifted right by 20 (its two 20-bit indices).
Eigen::Vector2d cell_centre(uint64_t cell, double cell_m) {
  const auto index = [](uint64_t bits) {  // sign-extended from 20 bits
    const auto v = static_cast<int64_t>(bits & 0xFFFFF);
    return v >= (int64_t{1} << 19) ? v - (int64_t{1} << 20) : v;
  };
  return {(static_cast<double>(index(cell >> 20)) + 0.5) * cell_m, (static_cast<double>(index(cell)) + 0.5) * cell_m};
}

struct CellError {
  uint64_t cell;  // its two 20-bit indices
  double error;
};

// Per cell seen by two or more lines, the largest difference between the lines' mean elevations
// there.
std::vector<CellError> cell_errors(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                   const ConsistencyConfig& config) {
  std::unordered_map<uint64_t, Spread> per_cell;
  for (const auto& [k, mean] : line_means(set, poses, config)) per_cell[k >> 20].add(mean);
  std::vector<CellError> errors;
  for (const auto& [cell, spread] : per_cell) {
    if (spread.lines >= 2) errors.push_back({cell, spread.hi - spread.lo});
  }
  return errors;
}

}  // namespace

ConsistencyReport consistency_error(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                    const ConsistencyConfig& config) {
  std::vector<double> errors;
  for (const CellError& e : cell_errors(set, poses, config)) errors.push_back(e.error);
  return report_of(std::move(errors), config);
}

double median_submap_side_m(const SubmapSet& set) {
  std::vector<double> sides;
  for (const Submap& s : set.submaps) {
    const Eigen::AlignedBox2f box = s.extent.isEmpty() ? extent_of(s.points) : s.extent;
    if (s.line >= 0 && !box.isEmpty()) sides.push_back(std::sqrt(static_cast<double>(box.volume())));
  }
  if (sides.empty()) return 0;
  std::nth_element(sides.begin(), sides.begin() + sides.size() / 2, sides.end());
  return sides[sides.size() / 2];
}

double p99_upper_by_blocks(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                           const ConsistencyConfig& config, double block_m, int replicates) {
  std::map<uint64_t, std::vector<double>> by_block;  // ordered: the same survey, the same bound
  for (const CellError& e : cell_errors(set, poses, config)) {
    const Eigen::Vector2d c = cell_centre(e.cell, config.cell_m);
    by_block[cell_line_key(static_cast<int64_t>(std::floor(c.x() / block_m)),
                           static_cast<int64_t>(std::floor(c.y() / block_m)), 0)]
        .push_back(e.error);
  }
  std::vector<const std::vector<double>*> blocks;
  std::size_t cells = 0;
  for (const auto& [key, errors] : by_block) blocks.push_back(&errors), cells += errors.size();
  if (blocks.empty() || replicates < 1) return 0;
  std::mt19937_64 random(blocks.size());
  std::uniform_int_distribution<std::size_t> pick(0, blocks.size() - 1);
  std::vector<double> p99s, sample;
  sample.reserve(2 * cells);
  for (int r = 0; r < replicates; ++r) {
    sample.clear();
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const auto& errors = *blocks[pick(random)];
      sample.insert(sample.end(), errors.begin(), errors.end());
    }
    const auto rank = static_cast<std::ptrdiff_t>(std::floor(0.99 * static_cast<double>(sample.size() - 1)));
    std::nth_element(sample.begin(), sample.begin() + rank, sample.end());
    p99s.push_back(sample[rank]);
  }
  std::sort(p99s.begin(), p99s.end());
  return p99s[static_cast<std::size_t>(std::ceil(0.99 * replicates)) - 1];
}

SiteConsistency site_consistency(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses,
                                 const ConsistencyConfig& config,
                                 const std::function<bool(const Eigen::Vector2d&)>& changed) {
  std::vector<int> survey_of_line(set.lines.size(), 0);
  for (const Submap& s : set.submaps) {
    if (s.line >= 0) {
      survey_of_line.at(s.line) = survey_of(set.survey_starts, s.index);
    }
  }
  const std::size_t surveys = set.survey_starts.size() + 1;
  std::unordered_map<uint64_t, std::vector<Spread>> per_cell;  // a spread per survey
  for (const auto& [k, mean] : line_means(set, poses, config)) {
    std::vector<Spread>& spreads = per_cell[k >> 20];
    spreads.resize(surveys);
    spreads[survey_of_line.at(k & 0xFFFFF)].add(mean);
  }
  std::vector<double> within, across;
  for (const auto& [cell, spreads] : per_cell) {
    const bool left_out = changed && changed(cell_centre(cell, config.cell_m));
    for (std::size_t a = 0; a < surveys; ++a) {
      if (spreads[a].lines >= 2) within.push_back(spreads[a].hi - spreads[a].lo);
      for (std::size_t b = a + 1; b < surveys && !left_out; ++b) {
        if (spreads[a].lines == 0 || spreads[b].lines == 0) continue;
        across.push_back(std::max(spreads[a].hi - spreads[b].lo, spreads[b].hi - spreads[a].lo));
      }
    }
  }
  return {report_of(std::move(within), config), report_of(std::move(across), config)};
}

std::vector<double> trajectory_errors(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> errors;
  for (const Submap& s : set.submaps) {
    if (!s.reference_pose) continue;
    errors.push_back((poses[s.index].translation() - s.reference_pose->translation()).head<2>().norm());
  }
  return errors;
}

std::vector<double> aligned_trajectory_errors(const SubmapSet& set, const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<Eigen::Vector2d> estimate, reference;
  for (const Submap& s : set.submaps) {
    if (!s.reference_pose) continue;
    estimate.push_back(poses[s.index].translation().head<2>());
    reference.push_back(s.reference_pose->translation().head<2>());
  }
  if (estimate.size() < 2) return trajectory_errors(set, poses);
  Eigen::Matrix2Xd from(2, estimate.size()), to(2, reference.size());
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    from.col(static_cast<Eigen::Index>(k)) = estimate[k];
    to.col(static_cast<Eigen::Index>(k)) = reference[k];
  }
  const Eigen::Matrix3d alignment = Eigen::umeyama(from, to, false);
  std::vector<double> errors;
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    const Eigen::Vector2d aligned = alignment.topLeftCorner<2, 2>() * estimate[k] + alignment.topRightCorner<2, 1>();
    errors.push_back((aligned - reference[k]).norm());
  }
  return errors;
}

std::optional<RelativePoseError> relative_pose_error(const SubmapSet& set, int from, int to,
                                                     const Eigen::Isometry3d& measured) {
  const auto& a = set.submaps[from].reference_pose;
  const auto& b = set.submaps[to].reference_pose;
  if (!a || !b) return std::nullopt;
  const Eigen::Isometry3d error = (a->inverse() * *b).inverse() * measured;
  return RelativePoseError{error.translation().norm(), error.translation().head<2>().norm(),
                           std::atan2(error.rotation()(1, 0), error.rotation()(0, 0)) * 180.0 / M_PI};
}

std::optional<EdgeErrorSigmas> edge_error_sigmas(const SubmapSet& set, int from, int to, const Eigen::Isometry3d& measured,
                                                 const Eigen::Vector3d& anchor,
                                                 const Eigen::Matrix<double, 6, 6>& information) {
  const auto& a = set.submaps[from].reference_pose;
  const auto& b = set.submaps[to].reference_pose;
  if (!a || !b) return std::nullopt;
  const Eigen::Isometry3d truth = a->inverse() * *b;
  const Eigen::Vector2d e_xy = (measured * anchor - truth * anchor).head<2>();
  const Eigen::Matrix3d turn = truth.rotation().transpose() * measured.rotation();
  const double e_yaw = std::atan2(turn(1, 0), turn(0, 0));
  const double horizontal2 = e_xy.dot(information.topLeftCorner<2, 2>() * e_xy);
  const Eigen::Vector3d r(-e_xy.x(), -e_xy.y(), e_yaw);
  const double joint2 = r.dot(xy_yaw_block(information) * r);
  return EdgeErrorSigmas{std::sqrt(std::max(0.0, horizontal2)), std::abs(e_yaw) * std::sqrt(std::max(0.0, information(5, 5))),
                         std::sqrt(std::max(0.0, joint2)), e_xy};
}

}  // namespace bathyslam

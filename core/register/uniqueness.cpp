#include "core/register/uniqueness.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace bathyslam {
namespace {

// Where a moved source cell falls on the target grid: the target cell below-left of it and the
// bilinear weights within. An offset of whole target cells moves the cell and keeps the weights,
// so the probe's offsets (a step of 1 m over 0.5 m cells) reuse one set of samples.
struct GridSample {
  int col = 0, row = 0;
  float fu = 0, fv = 0;
  double down = 0;  // the source's depth there (target frame, z down)
};

std::vector<GridSample> samples_at(const TerrainGrid& target, const std::vector<Eigen::Vector3d>& moved,
                                   const Eigen::Vector2d& offset) {
  std::vector<GridSample> samples;
  samples.reserve(moved.size());
  for (const Eigen::Vector3d& p : moved) {
    const double u = (p.x() + offset.x() - target.origin.x()) / target.cell_m;
    const double v = (p.y() + offset.y() - target.origin.y()) / target.cell_m;
    const double c = std::floor(u), r = std::floor(v);
    samples.push_back({static_cast<int>(c), static_cast<int>(r), static_cast<float>(u - c), static_cast<float>(v - r), p.z()});
  }
  return samples;
}

// Target elevation (up) at a sample moved by (dc, dr) cells, bilinear over valid cells; NaN off
// the grid or next to a hole.
float elevation_at(const TerrainGrid& grid, const GridSample& s, int dc, int dr) {
  const int c = s.col + dc, r = s.row + dr;
  if (c < 0 || r < 0 || c + 1 >= grid.cols() || r + 1 >= grid.rows()) return std::numeric_limits<float>::quiet_NaN();
  const uint8_t* valid0 = grid.valid.ptr<uint8_t>(r);
  const uint8_t* valid1 = grid.valid.ptr<uint8_t>(r + 1);
  if (!valid0[c] || !valid0[c + 1] || !valid1[c] || !valid1[c + 1]) return std::numeric_limits<float>::quiet_NaN();
  const float* row0 = grid.elevation.ptr<float>(r);
  const float* row1 = grid.elevation.ptr<float>(r + 1);
  const float fu = s.fu, fv = s.fv;
  return (1 - fv) * ((1 - fu) * row0[c] + fu * row0[c + 1]) + fv * ((1 - fu) * row1[c] + fu * row1[c + 1]);
}

struct Cost {
  double mean_square = std::numeric_limits<double>::infinity();
  int cells = 0;
};

// Mean squared difference between the samples moved by (dc, dr) cells and the target, their
// mean difference removed (a depth bias is not a misalignment).
Cost cost_at(const TerrainGrid& target, const std::vector<GridSample>& samples, int dc, int dr) {
  double sum = 0, sum_sq = 0;
  int n = 0;
  for (const GridSample& s : samples) {
    const float up = elevation_at(target, s, dc, dr);
    if (std::isnan(up)) continue;
    const double d = -s.down - up;
    sum += d;
    sum_sq += d * d;
    ++n;
  }
  Cost c;
  c.cells = n;
  if (n > 0) c.mean_square = std::max(0.0, sum_sq / n - (sum / n) * (sum / n));
  return c;
}

// The cost at a horizontal offset in metres: by whole cells from `at_answer` when the offset is
// a whole number of cells, else from samples taken there.
Cost cost_at(const TerrainGrid& target, const std::vector<Eigen::Vector3d>& moved,
             const std::vector<GridSample>& at_answer, const Eigen::Vector2d& offset) {
  const Eigen::Vector2d cells = offset / target.cell_m;
  const Eigen::Vector2d whole = cells.array().round();
  if ((cells - whole).cwiseAbs().maxCoeff() < 1e-9) {
    return cost_at(target, at_answer, static_cast<int>(whole.x()), static_cast<int>(whole.y()));
  }
  return cost_at(target, samples_at(target, moved, offset), 0, 0);
}

}  // namespace

double Uniqueness::distinctness() const {
  if (!probed) return 0.0;
  return alternative_cost_m2 / std::max(cost_at_answer_m2, misfit_floor_m2);
}

double Uniqueness::nearby_improvement() const {
  if (!probed) return 1.0;
  return std::max(cost_at_answer_m2, misfit_floor_m2) / std::max(nearby_cost_m2, misfit_floor_m2);
}

bool Uniqueness::unique() const {
  return probed && std::find(competitors.begin(), competitors.end(), true) == competitors.end();
}

std::vector<Eigen::Vector2d> Uniqueness::competitor_offsets(bool open) const {
  std::vector<Eigen::Vector2d> offsets;
  const int side = 2 * reach + 1;
  const std::vector<bool>& mask = open ? open_competitors : competitors;
  for (std::size_t k = 0; k < mask.size(); ++k) {
    if (!mask[k]) continue;
    const int i = static_cast<int>(k % side) - reach, j = static_cast<int>(k / side) - reach;
    offsets.emplace_back(i * step_m, j * step_m);
  }
  return offsets;
}

Uniqueness probe_uniqueness(const TerrainGrid& target, const TerrainGrid& source, const Eigen::Isometry3d& source_to_target,
                            const UniquenessConfig& config) {
  Uniqueness u;
  u.misfit_floor_m2 = config.misfit_floor_m2;
  std::vector<Eigen::Vector3d> moved;
  for (int r = 0; r < source.rows(); ++r) {
    for (int c = 0; c < source.cols(); ++c) {
      if (!source.valid.at<uint8_t>(r, c)) continue;
      const Eigen::Vector2d xy = source.position(c, r);
      moved.push_back(source_to_target * Eigen::Vector3d(xy.x(), xy.y(), -source.elevation.at<float>(r, c)));
    }
  }
  // Only the cells that overlap at the answer take part, so every offset compares the same ground.
  std::vector<Eigen::Vector3d> overlap;
  std::vector<GridSample> overlap_samples;
  const std::vector<GridSample> samples = samples_at(target, moved, Eigen::Vector2d::Zero());
  for (std::size_t i = 0; i < moved.size(); ++i) {
    if (std::isnan(elevation_at(target, samples[i], 0, 0))) continue;
    overlap.push_back(moved[i]);
    overlap_samples.push_back(samples[i]);
  }
  const Cost at_answer = cost_at(target, overlap_samples, 0, 0);
  if (at_answer.cells < 50) return u;

  const int reach = static_cast<int>(std::floor(config.search_radius_m / config.step_m));
  const int side = 2 * reach + 1;
  std::vector<double> cost(static_cast<std::size_t>(side) * side, std::numeric_limits<double>::infinity());
  std::vector<double> compared, local;
  const int min_cells = static_cast<int>(config.min_overlap_share * at_answer.cells);
  for (int j = -reach; j <= reach; ++j) {
    for (int i = -reach; i <= reach; ++i) {
      const Eigen::Vector2d offset(i * config.step_m, j * config.step_m);
      if (offset.norm() > config.search_radius_m) continue;
      const Cost c = cost_at(target, overlap, overlap_samples, offset);
      if (c.cells < min_cells) continue;
      cost[static_cast<std::size_t>(j + reach) * side + (i + reach)] = c.mean_square;
      compared.push_back(c.mean_square);
      if (offset.norm() <= config.local_radius_m) local.push_back(c.mean_square);
    }
  }
  if (compared.size() < 9) return u;
  u.probed = true;
  u.cost_at_answer_m2 = at_answer.mean_square;
  std::nth_element(compared.begin(), compared.begin() + compared.size() / 2, compared.end());
  u.typical_cost_m2 = compared[compared.size() / 2];
  if (!local.empty()) {
    std::nth_element(local.begin(), local.begin() + local.size() / 2, local.end());
    u.local_cost_m2 = local[local.size() / 2];
  }

  // Whole cells within the exclusion radius reuse the answer's samples.
  u.nearby_cost_m2 = u.cost_at_answer_m2;
  const int near_cells = static_cast<int>(std::floor(config.exclusion_m / target.cell_m));
  for (int dr = -near_cells; dr <= near_cells; ++dr) {
    for (int dc = -near_cells; dc <= near_cells; ++dc) {
      if ((dc == 0 && dr == 0) || std::hypot(dc, dr) * target.cell_m >= config.exclusion_m) continue;
      const Cost c = cost_at(target, overlap_samples, dc, dr);
      if (c.cells < min_cells || c.mean_square >= u.nearby_cost_m2) continue;
      u.nearby_cost_m2 = c.mean_square;
      u.nearby_offset_m = Eigen::Vector2d(dc, dr) * target.cell_m;
    }
  }

  // Competitors: every offset outside the exclusion radius that fits nearly as well, a basin's
  // shoulders too (a direct answer on a weakly textured patch is not known to lie in the right
  // basin). The best local minimum among all offsets is the alternative.
  u.reach = reach;
  u.step_m = config.step_m;
  u.competitors.assign(cost.size(), false);
  const double competing = config.competitor_ratio * std::max(u.cost_at_answer_m2, u.misfit_floor_m2);
  for (int j = -reach; j <= reach; ++j) {
    for (int i = -reach; i <= reach; ++i) {
      const std::size_t k = static_cast<std::size_t>(j + reach) * side + (i + reach);
      u.competitors[k] = std::hypot(i, j) * config.step_m >= config.exclusion_m && cost[k] < competing;
    }
  }
  const auto compared_at = [&](int i, int j) {
    return std::abs(i) <= reach && std::abs(j) <= reach && std::isfinite(cost[static_cast<std::size_t>(j + reach) * side + (i + reach)]);
  };
  u.open_competitors.assign(cost.size(), false);
  for (int j = -reach; j <= reach; ++j) {
    for (int i = -reach; i <= reach; ++i) {
      const std::size_t k = static_cast<std::size_t>(j + reach) * side + (i + reach);
      u.open_competitors[k] = u.competitors[k] && !(compared_at(i - 1, j) && compared_at(i + 1, j) &&
                                                    compared_at(i, j - 1) && compared_at(i, j + 1));
    }
  }
  u.alternative_cost_m2 = u.typical_cost_m2;
  auto at = [&](int i, int j) { return cost[static_cast<std::size_t>(j + reach) * side + (i + reach)]; };
  for (int j = -reach + 1; j < reach; ++j) {
    for (int i = -reach + 1; i < reach; ++i) {
      const double here = at(i, j);
      if (!std::isfinite(here) || std::hypot(i, j) * config.step_m < config.exclusion_m) continue;
      bool minimum = true;
      for (int dj = -1; dj <= 1 && minimum; ++dj) {
        for (int di = -1; di <= 1 && minimum; ++di) minimum = (di == 0 && dj == 0) || here <= at(i + di, j + dj);
      }
      if (minimum && here < u.alternative_cost_m2) {
        u.alternative_cost_m2 = here;
        u.alternative_offset_m = Eigen::Vector2d(i * config.step_m, j * config.step_m);
      }
    }
  }
  return u;
}

}  // namespace bathyslam

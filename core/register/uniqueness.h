#pragma once
// register (uniqueness): is a registration's answer the only good alignment of the pair? On a
// periodic seabed (sand waves, megaripples, parallel ridges) the terrain matches itself one
// wavelength along, and feature matching can lock onto any of those aliases with every match
// agreeing: RANSAC sees no competitor and GICP refines the alias to a good residual. The probe
// slides the source's terrain over the target's around the answer and asks whether another
// horizontal offset fits nearly as well.
#include <vector>

#include <Eigen/Geometry>

#include "core/features/terrain_grid.h"

namespace bathyslam {

struct UniquenessConfig {
  // Offsets probed, horizontally in the target frame: as far as a wrong alias could sit from the
  // answer and still reach the overlap (the matching gate is 30 m).
  double search_radius_m = 24.0;
  double step_m = 1.0;  // half the shortest wavelength that makes features at 0.5 m cells
  // Minima nearer the answer than this belong to its own basin.
  double exclusion_m = 3.0;
  // An offset must keep this share of the cells the answer overlaps, or it compares too little.
  double min_overlap_share = 0.5;
  // How far from the answer the truth may lie when nothing pins the answer horizontally (the
  // direct path keeps its guess's horizontal error: p50 2-6 m on `lake`): the relief within this
  // radius is how wrong a depth measured at the wrong place can be.
  double local_radius_m = 5.0;
  // An offset outside the exclusion radius whose misfit is under this many times the answer's
  // (floored as in `distinctness`) competes with it (Uniqueness::competitors): the same ratio as
  // acceptance.min_distinctness, an RMS misfit under 5x the answer's.
  double competitor_ratio = 25.0;
  // The misfit a perfect alignment still leaves, (2 cm)² at the lake's footprint: ratios of
  // misfits are taken against at least this, so that sounding noise alone does not make an answer
  // look unique.
  double misfit_floor_m2 = 4e-4;
  template <typename Field>
  void fields(Field&& field) {
    field("search_radius_m", search_radius_m, 1, 1e5);
    field("step_m", step_m, 0.1, 1e5);
    field("exclusion_m", exclusion_m, 0, 1e5);
    field("min_overlap_share", min_overlap_share, 0.01, 1);
    field("local_radius_m", local_radius_m, 0, 1e5);
    field("competitor_ratio", competitor_ratio, 1, 1e6);
    field("misfit_floor_m2", misfit_floor_m2, 0, 1e6);
  }
};

struct Uniqueness {
  bool probed = false;  // false: too little overlap to compare
  double cost_at_answer_m2 = 0;  // mean squared elevation difference, mean removed
  double typical_cost_m2 = 0;    // median over all offsets probed: what a misalignment costs (reported)
  double local_cost_m2 = 0;      // median over the offsets within local_radius_m
  double alternative_cost_m2 = 0;  // the lowest local minimum outside the exclusion radius
  // The lowest cost within the exclusion radius, probed a grid cell apart: an answer at the
  // bottom of its own basin fits about as well as anything this near it, one that is not (GICP
  // stopped on a slope or in a dent of its cost) fits many times worse.
  double nearby_cost_m2 = 0;
  Eigen::Vector2d nearby_offset_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d alternative_offset_m = Eigen::Vector2d::Zero();
  double misfit_floor_m2 = UniquenessConfig{}.misfit_floor_m2;  // the probe's
  // How much worse the best alternative fits than the answer: the ratio of their mean squared
  // misfits, the answer's floored at `misfit_floor_m2`. About 1 when another offset fits as well
  // (a periodic or flat seabed); in the hundreds on textured ground, where only the answer
  // leaves nothing but sounding noise.
  double distinctness() const;
  // How many times better the best nearby offset fits than the answer (both floored at
  // `misfit_floor_m2`): about 1 at the bottom of the basin.
  double nearby_improvement() const;
  // Every offset that competes with the answer (UniquenessConfig::competitor_ratio), as a mask
  // over the probe's square of (2·reach + 1)² offsets `step_m` apart, row by row from
  // (−reach, −reach): a bit each, so that a flat bottom, where every offset competes, costs
  // 300 bytes and not 30 KB.
  int reach = 0;
  double step_m = 0;
  std::vector<bool> competitors;
  // Competitors beside an offset that was not compared (beyond the search radius, or too little
  // overlap there): the competing region goes on past what the probe saw. Same layout.
  std::vector<bool> open_competitors;
  // The competing offsets (target frame, m); with `open`, those at the probe's edge only.
  std::vector<Eigen::Vector2d> competitor_offsets(bool open = false) const;
  // Probed, and nothing within reach competes: the answer is the terrain's, whatever the start.
  bool unique() const;
};

// `source_to_target` maps the source submap frame into the target's (z down); the grids are the
// submaps' own (features/terrain_grid.h).
Uniqueness probe_uniqueness(const TerrainGrid& target, const TerrainGrid& source, const Eigen::Isometry3d& source_to_target,
                            const UniquenessConfig& config = {});

}  // namespace bathyslam

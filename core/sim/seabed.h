#pragma once
// The seabed kinds other than the lake: each a relief about the mean depth, evaluated anywhere,
// which Terrain samples onto its grid.
#include <memory>
#include <random>

#include <Eigen/Core>

#include "core/sim/terrain.h"

namespace bathyslam::sim {

struct Ground {
  double height = 0;     // metres above the mean depth
  double roughness = 0;  // 0 smooth ground, 1 rough (see Terrain::roughness_weight)
};

class Seabed {
 public:
  virtual ~Seabed() = default;
  virtual Ground at(const Eigen::Vector2d& p) const = 0;
  // Its sand waves moved `distance_m` across their crests (a later epoch of a site); nothing else
  // moves, and the seabed's mean height stays the one it was centred on.
  virtual void migrate_sand_waves(double /*distance_m*/) {}
};

// A seabed of `kind` (not kLake) laid out over `area` (channels cross it, the slope break runs
// through its centre), its mean height over `area` zero. Draws its shape from `rng`.
std::unique_ptr<Seabed> make_seabed(TerrainKind kind, const TerrainConfig& config,
                                    const Area& area, std::mt19937_64& rng);

}  // namespace bathyslam::sim

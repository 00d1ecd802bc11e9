#pragma once
// site: several surveys of one site (issue 33), as a site is re-surveyed to follow what moved.
// Epoch 1 flies the scenario's pattern; each later epoch flies it turned about the block's centre
// (180° and 5° more each epoch: other headings, another start) and, every other epoch, moved half
// a line spacing (other lines), with its own drift, a start fix off by a few metres, and the seabed changed
// since epoch 1: a scour pit, an object dropped on the bottom, an area dredged, and sand waves
// (where the seabed has them) migrated across their crests.
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/sim/terrain.h"
#include "core/sim/trajectory.h"

namespace bathyslam::sim {

// How far sand waves move between two surveys a month apart, at the lake's scale: migration
// rates of sand waves on shelves are metres to tens of metres a year, faster under tides and storms.
inline constexpr double kSandMigrationPerEpochM = 2.0;

// One change of the seabed between epoch 1 and later epochs, in the local map frame.
struct SeabedChange {
  std::string kind;         // "scour pit", "object", "dredged area"
  Eigen::Vector2d centre;   // m
  Eigen::Vector2d size_m;   // across x and y (a pit's diameter twice)
  double height_m = 0;      // elevation gained (negative: lost) at its deepest or highest
};

// The changes placed within `block` (the epoch-1 lines' area), their sizes `scale` times the
// lake's (a survey flown higher sees a larger seabed).
std::vector<SeabedChange> seabed_changes(const Area& block, double scale);

// The elevation `change` adds at (x, y).
double elevation_change(const SeabedChange& change, double x, double y);

// Epoch `epoch` (1, 2, ...) of the scenario's `lines`, `spacing_m` apart.
std::vector<LineSpec> epoch_lines(const std::vector<LineSpec>& lines, int epoch, double spacing_m);

// The seabed's area for every epoch, widened by `margin_m`: the same terrain whichever epoch is
// simulated.
Area site_area(const std::vector<LineSpec>& lines, double spacing_m, double margin_m);

// Where epoch `epoch`'s dead reckoning started from, as its start fix put it: x, y (m) and heading
// (rad, counter-clockwise) off the truth; zero for epoch 1, the site's datum.
Eigen::Vector3d start_fix_error(uint64_t seed, int epoch);

nlohmann::json to_json(const SeabedChange& change);
// A change as survey.json records it (to_json's inverse).
SeabedChange seabed_change_from_json(const nlohmann::json& json);

}  // namespace bathyslam::sim

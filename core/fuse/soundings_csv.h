#pragma once
// The corrected soundings as a point cloud, for users who grid elsewhere: one CSV row per
// sounding, `easting,northing,elevation,line,submap` (metres in the survey's CRS, elevation up,
// negative below the datum; line and submap as report.json numbers them, line -1 in a turn).
// Written submap by submap through a buffered stream, so memory does not grow with the survey.
#include <cstdint>
#include <filesystem>
#include <span>

#include <Eigen/Geometry>

#include "core/submaps/submap.h"

namespace bathyslam {

inline constexpr const char* kSoundingsHeader = "easting,northing,elevation,line,submap";

// Writes every sounding of `set` placed by `poses` (one per submap) to `path`, atomically;
// returns how many. Throws std::runtime_error naming the path when it cannot.
std::uint64_t write_soundings_csv(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses,
                                  const std::filesystem::path& path);

}  // namespace bathyslam

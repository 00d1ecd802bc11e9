#pragma once
// The survey pattern of a scenario and the vehicle driving it: straight survey lines joined by
// turns, sampled at a fixed step so that pings and navigation take exact true states.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/sim/terrain.h"
#include "core/types/survey.h"

namespace bathyslam::sim {

enum class Scenario { kSmall, kLake, kLarge, kXLarge };

Scenario parse_scenario(const std::string& name);  // throws std::invalid_argument
std::string to_string(Scenario scenario);

struct LineSpec {
  Eigen::Vector2d start;
  Eigen::Vector2d end;
};

// Lawnmower lines (east-west, alternating direction) then check lines (north-south) crossing
// them, in the local map frame with the first line starting at the origin. Another line spacing
// keeps the number of lines and stretches the check lines with the block, so they still cross
// all of it.
std::vector<LineSpec> survey_pattern(Scenario scenario,
                                     std::optional<double> line_spacing_m = std::nullopt);

double default_line_spacing_m(Scenario scenario);

// Half the line spacing, so lawnmower turns are semicircles, but no tighter than the vehicle can
// turn; below twice that the Dubins path loops out to make the turn.
double lawnmower_turn_radius_m(double line_spacing_m);

struct MotionConfig {
  double speed_m_s = 2.0;
  double turn_radius_m = 15.0;  // lawnmower_turn_radius_m of the scenarios' 30 m spacing
  double vehicle_depth_m = 1.0;
  double run_in_m = 20.0;       // straight run before the first line
  double step_s = 0.025;     // state sampling; pings and nav take every few steps
  double start_time = 1720000000.0;
  uint64_t seed = 1;         // attitude oscillation phases
};

// The true state of the vehicle at one step.
struct VehicleState {
  double time = 0;
  double x = 0;          // east, local frame (m)
  double y = 0;          // north, local frame (m)
  double depth_m = 0;
  double roll_deg = 0;
  double pitch_deg = 0;
  double heading_deg = 0;  // clockwise from north, in [0, 360)
};

// Drives the pattern: each line straight, joined to the next by the shortest turn-straight-turn
// path at the turn radius (a Dubins path), recording the state every step.
std::vector<VehicleState> drive(const std::vector<LineSpec>& lines, const MotionConfig& config);

// Every `stride`-th state as a navigation sample, shifted from the local frame by (east, north).
std::vector<NavSample> navigation_of(const std::vector<VehicleState>& states, std::size_t stride,
                                     double east = 0.0, double north = 0.0);

// The area covered by the pattern's lines, widened by `margin_m`.
Area pattern_area(const std::vector<LineSpec>& lines, double margin_m);

}  // namespace bathyslam::sim

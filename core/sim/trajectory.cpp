#include "core/sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "core/sim/random.h"

namespace bathyslam::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMinTurnRadiusM = 10.0;  // a small survey AUV's tightest turn at 2 m/s

struct PatternSize {
  int lines;
  double line_length_m;
  double spacing_m;
  int check_lines;
  double check_length_m;
};

PatternSize pattern_size(Scenario scenario) {
  switch (scenario) {
    // The paper's lake trial: 7 lines of 738 m, 30 m apart; 3 check lines of 294 m.
    case Scenario::kLake: return {7, 738.0, 30.0, 3, 294.0};
    // A tenth of the distance travelled, same spacing and depth, so registration behaves alike.
    case Scenario::kSmall: return {4, 100.0, 30.0, 2, 110.0};
    // Ten times the area: the lake pattern scaled by sqrt(10) in both directions.
    case Scenario::kLarge: return {22, 2334.0, 30.0, 9, 930.0};
    // Four times `large` (issue 35's scaling curve): its pattern doubled in both directions.
    case Scenario::kXLarge: return {44, 4668.0, 30.0, 18, 1860.0};
  }
  throw std::invalid_argument("unknown scenario");
}

double block_height_m(const PatternSize& size) { return (size.lines - 1) * size.spacing_m; }

PatternSize pattern_size(Scenario scenario, std::optional<double> line_spacing_m) {
  PatternSize size = pattern_size(scenario);
  if (!line_spacing_m) return size;
  if (!(*line_spacing_m > 0)) throw std::invalid_argument("line spacing must be positive");
  // Check lines overhang the block as much as at the scenario's spacing.
  const double overhang_m = size.check_length_m - block_height_m(size);
  size.spacing_m = *line_spacing_m;
  size.check_length_m = block_height_m(size) + overhang_m;
  return size;
}

}  // namespace

Scenario parse_scenario(const std::string& name) {
  if (name == "small") return Scenario::kSmall;
  if (name == "lake") return Scenario::kLake;
  if (name == "large") return Scenario::kLarge;
  if (name == "xlarge") return Scenario::kXLarge;
  throw std::invalid_argument("unknown scenario '" + name + "' (expected small, lake, large or xlarge)");
}

std::string to_string(Scenario scenario) {
  switch (scenario) {
    case Scenario::kSmall: return "small";
    case Scenario::kLake: return "lake";
    case Scenario::kLarge: return "large";
    case Scenario::kXLarge: return "xlarge";
  }
  return "?";
}

double default_line_spacing_m(Scenario scenario) { return pattern_size(scenario).spacing_m; }

double lawnmower_turn_radius_m(double line_spacing_m) {
  return std::max(kMinTurnRadiusM, 0.5 * line_spacing_m);
}

std::vector<LineSpec> survey_pattern(Scenario scenario, std::optional<double> line_spacing_m) {
  const PatternSize size = pattern_size(scenario, line_spacing_m);
  std::vector<LineSpec> lines;
  for (int i = 0; i < size.lines; ++i) {
    const double y = i * size.spacing_m;
    const Eigen::Vector2d west(0.0, y), east(size.line_length_m, y);
    lines.push_back(i % 2 == 0 ? LineSpec{west, east} : LineSpec{east, west});
  }
  const double block_height = block_height_m(size);
  const double south = 0.5 * (block_height - size.check_length_m);
  const double north = south + size.check_length_m;
  // Check lines start next to where the lawnmower block ends (its north-east or north-west
  // corner) and run north to south first, so the transit to them is short.
  const bool block_ends_east = size.lines % 2 == 1;
  for (int k = 0; k < size.check_lines; ++k) {
    const int from_end = block_ends_east ? size.check_lines - 1 - k : k;
    const double x = size.line_length_m * (from_end + 1) / (size.check_lines + 1);
    const Eigen::Vector2d s(x, south), n(x, north);
    lines.push_back(k % 2 == 0 ? LineSpec{n, s} : LineSpec{s, n});
  }
  return lines;
}

std::vector<NavSample> navigation_of(const std::vector<VehicleState>& states, std::size_t stride,
                                     double east, double north) {
  std::vector<NavSample> nav;
  for (std::size_t i = 0; i < states.size(); i += stride) {
    const VehicleState& v = states[i];
    nav.push_back({v.time, v.x + east, v.y + north, v.depth_m, v.roll_deg, v.pitch_deg, v.heading_deg});
  }
  return nav;
}

Area pattern_area(const std::vector<LineSpec>& lines, double margin_m) {
  Area area{lines.front().start, lines.front().start};
  for (const LineSpec& l : lines) {
    for (const Eigen::Vector2d& p : {l.start, l.end}) {
      area.min = area.min.cwiseMin(p);
      area.max = area.max.cwiseMax(p);
    }
  }
  area.min.array() -= margin_m;
  area.max.array() += margin_m;
  return area;
}

namespace {

// A piece of the vehicle's path: straight (curvature 0) or an arc of constant curvature,
// positive turning left. Angles here are mathematical: counter-clockwise from east.
struct Segment {
  Eigen::Vector2d start;
  double theta = 0;
  double length = 0;
  double curvature = 0;

  Eigen::Vector2d position(double s) const {
    if (curvature == 0) return start + s * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    const double t = theta + curvature * s;
    return start + Eigen::Vector2d(std::sin(t) - std::sin(theta), std::cos(theta) - std::cos(t)) /
                       curvature;
  }
  double heading(double s) const { return theta + curvature * s; }
  Segment rest_from(double s) const { return {position(s), heading(s), length - s, curvature}; }
};

double mod_2pi(double a) {
  a = std::fmod(a, 2 * M_PI);
  return a < 0 ? a + 2 * M_PI : a;
}

// Shortest of the four turn-straight-turn paths (LSL, RSR, LSR, RSL) from pose (p0, theta0) to
// pose (p1, theta1) with turns of radius r.
std::vector<Segment> dubins_csc(const Eigen::Vector2d& p0, double theta0, const Eigen::Vector2d& p1,
                                double theta1, double r) {
  auto centre = [r](const Eigen::Vector2d& p, double theta, int side) {  // side +1 left, -1 right
    return Eigen::Vector2d(p + side * r * Eigen::Vector2d(-std::sin(theta), std::cos(theta)));
  };
  std::vector<Segment> best;
  double best_length = std::numeric_limits<double>::infinity();
  for (int first : {+1, -1}) {
    for (int last : {+1, -1}) {
      const Eigen::Vector2d c0 = centre(p0, theta0, first), c1 = centre(p1, theta1, last);
      const Eigen::Vector2d d = c1 - c0;
      const double distance = d.norm(), alpha = std::atan2(d.y(), d.x());
      double straight = distance, phi = alpha;
      if (first != last) {  // inner tangent: the circles must not overlap
        if (distance < 2 * r) continue;
        straight = std::sqrt(distance * distance - 4 * r * r);
        phi = alpha + first * std::atan2(2 * r, straight);
      }
      const double arc0 = mod_2pi(first * (phi - theta0));
      const double arc1 = mod_2pi(last * (theta1 - phi));
      const double length = r * (arc0 + arc1) + straight;
      if (length >= best_length) continue;
      best_length = length;
      const Segment turn0{p0, theta0, r * arc0, first / r};
      const Segment line{turn0.position(turn0.length), phi, straight, 0.0};
      const Segment turn1{line.position(straight), phi, r * arc1, last / r};
      best = {turn0, line, turn1};
    }
  }
  return best;
}

double math_angle(const Eigen::Vector2d& d) { return std::atan2(d.y(), d.x()); }

}  // namespace

std::vector<VehicleState> drive(const std::vector<LineSpec>& lines, const MotionConfig& config) {
  // The path: a run-in, then each line, joined to the next by a Dubins path.
  std::vector<Segment> path;
  const Eigen::Vector2d first_dir = (lines[0].end - lines[0].start).normalized();
  path.push_back({lines[0].start - config.run_in_m * first_dir, math_angle(first_dir),
                  config.run_in_m, 0.0});
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const Eigen::Vector2d d = lines[k].end - lines[k].start;
    if (k > 0) {
      const LineSpec& previous = lines[k - 1];
      for (const Segment& s : dubins_csc(previous.end, math_angle(previous.end - previous.start),
                                         lines[k].start, math_angle(d), config.turn_radius_m)) {
        if (s.length > 0) path.push_back(s);
      }
    }
    path.push_back({lines[k].start, math_angle(d), d.norm(), 0.0});
  }

  auto rng = make_rng(config.seed, kAttitudeStream);
  std::uniform_real_distribution<double> phase(0.0, 2 * M_PI);
  const double roll_phase = phase(rng), pitch_phase = phase(rng), heave_phase = phase(rng);
  // Times are whole milliseconds so they print short and read back exactly.
  const auto step_ms = static_cast<long long>(std::llround(config.step_s * 1000.0));
  const auto start_ms = static_cast<long long>(std::llround(config.start_time * 1000.0));
  const double ds = config.speed_m_s * config.step_s;

  std::vector<VehicleState> states;
  long long step = 0;
  double s = 0;  // distance into the current segment
  for (const Segment& segment : path) {
    for (; s < segment.length; s += ds, ++step) {
      const double elapsed = static_cast<double>(step * step_ms) / 1000.0;
      // Heading is clockwise from north; a left turn (positive curvature) lowers it.
      const double heading_rate_deg_s = -segment.curvature * config.speed_m_s / kDeg;
      const Eigen::Vector2d p = segment.position(s);
      VehicleState v;
      v.time = static_cast<double>(start_ms + step * step_ms) / 1000.0;
      v.x = p.x();
      v.y = p.y();
      v.depth_m = config.vehicle_depth_m + 0.03 * std::sin(2 * M_PI * elapsed / 20.0 + heave_phase);
      // Bank into turns, plus the slow oscillations of a vehicle in a little swell.
      v.roll_deg = 0.3 * heading_rate_deg_s + 0.8 * std::sin(2 * M_PI * elapsed / 6.3 + roll_phase);
      v.pitch_deg = 0.4 * std::sin(2 * M_PI * elapsed / 9.1 + pitch_phase);
      v.heading_deg = std::fmod(std::fmod(90.0 - segment.heading(s) / kDeg, 360.0) + 360.0, 360.0);
      states.push_back(v);
    }
    s -= segment.length;
  }
  return states;
}

}  // namespace bathyslam::sim

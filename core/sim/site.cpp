#include "core/sim/site.h"

#include <algorithm>
#include <cmath>

#include "core/sim/random.h"

namespace bathyslam::sim {
namespace {

// A surface GPS fix before the dive and the descent: a few metres, a degree of heading.
constexpr double kStartFixSigmaM = 2.0;
constexpr double kStartFixSigmaHeadingRad = 0.01;

Eigen::Vector2d turned(const Eigen::Vector2d& p, const Eigen::Vector2d& centre, double angle_rad) {
  return centre + Eigen::Rotation2Dd(angle_rad) * (p - centre);
}

Eigen::Vector2d centre_of(const Area& a) { return 0.5 * (a.min + a.max); }

}  // namespace

std::vector<SeabedChange> seabed_changes(const Area& block, double scale) {
  const Eigen::Vector2d c = centre_of(block);
  const double w = block.max.x() - block.min.x(), h = block.max.y() - block.min.y();
  return {
      {"scour pit", c + Eigen::Vector2d(0.2 * w, 0.1 * h), scale * Eigen::Vector2d(10, 10), -0.5 * scale},
      {"object", c + Eigen::Vector2d(-0.2 * w, 0.05 * h), scale * Eigen::Vector2d(2, 2), 1.0 * scale},
      {"dredged area", c + Eigen::Vector2d(0.0, -0.15 * h), scale * Eigen::Vector2d(40, 30), -0.3 * scale},
  };
}

double elevation_change(const SeabedChange& change, double x, double y) {
  const Eigen::Vector2d d = Eigen::Vector2d(x, y) - change.centre;
  const Eigen::Vector2d half = 0.5 * change.size_m;
  if (change.kind == "scour pit") {
    const double r = d.norm() / half.x();
    return r < 1 ? change.height_m * 0.5 * (1 + std::cos(M_PI * r)) : 0;
  }
  if (change.kind == "object") return (std::abs(d.x()) < half.x() && std::abs(d.y()) < half.y()) ? change.height_m : 0;
  // Dredged: the cut's banks slope over a metre (of the lake's scale).
  const double inside = std::min(half.x() - std::abs(d.x()), half.y() - std::abs(d.y()));
  const double batter = change.size_m.x() / 40;
  return change.height_m * std::clamp(inside / batter, 0.0, 1.0);
}

std::vector<LineSpec> epoch_lines(const std::vector<LineSpec>& lines, int epoch, double spacing_m) {
  if (epoch <= 1) return lines;
  const Eigen::Vector2d centre = centre_of(pattern_area(lines, 0));
  const double turn = (epoch - 1) * (M_PI + 5 * M_PI / 180);
  // Half a spacing across the epoch-1 lines (they run east-west) every other epoch, then turned.
  const Eigen::Vector2d across(0, 0.5 * spacing_m * ((epoch - 1) % 2));
  std::vector<LineSpec> out;
  for (const LineSpec& l : lines) out.push_back({turned(l.start + across, centre, turn), turned(l.end + across, centre, turn)});
  return out;
}

Area site_area(const std::vector<LineSpec>& lines, double spacing_m, double margin_m) {
  // Any turn about the centre stays within the circle through the block's corners.
  const Area block = pattern_area(lines, 0);
  const double reach = 0.5 * (block.max - block.min).norm() + 0.5 * spacing_m + margin_m;
  const Eigen::Vector2d centre = centre_of(block);
  return {centre.array() - reach, centre.array() + reach};
}

Eigen::Vector3d start_fix_error(uint64_t seed, int epoch) {
  if (epoch <= 1) return Eigen::Vector3d::Zero();
  auto rng = make_rng(seed, kStartFixStream, static_cast<uint64_t>(epoch));
  std::normal_distribution<double> unit(0, 1);
  const double x = kStartFixSigmaM * unit(rng), y = kStartFixSigmaM * unit(rng);
  return {x, y, kStartFixSigmaHeadingRad * unit(rng)};
}

nlohmann::json to_json(const SeabedChange& change) {
  return {{"kind", change.kind},
          {"centre_m", {change.centre.x(), change.centre.y()}},
          {"size_m", {change.size_m.x(), change.size_m.y()}},
          {"height_m", change.height_m}};
}

SeabedChange seabed_change_from_json(const nlohmann::json& json) {
  return {json.at("kind").get<std::string>(),
          {json.at("centre_m")[0].get<double>(), json.at("centre_m")[1].get<double>()},
          {json.at("size_m")[0].get<double>(), json.at("size_m")[1].get<double>()},
          json.at("height_m").get<double>()};
}

}  // namespace bathyslam::sim

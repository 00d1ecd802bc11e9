#include "core/sync/nav_interpolation.h"

#include <algorithm>

#include "core/types/pose.h"

namespace bathyslam {

std::optional<NavSample> interpolate_nav(const std::vector<NavSample>& nav, double time) {
  if (nav.empty() || time < nav.front().time || time > nav.back().time) return std::nullopt;
  const auto after = std::lower_bound(nav.begin(), nav.end(), time,
                                      [](const NavSample& s, double t) { return s.time < t; });
  if (after->time == time || after == nav.begin()) return *after;
  const NavSample& a = *(after - 1);
  const NavSample& b = *after;
  const double f = (time - a.time) / (b.time - a.time);

  // Attitude in the map frame, so the slerp takes the short way through heading wrap-around.
  const Eigen::Quaterniond qa(vehicle_to_map_rotation(a.roll_deg, a.pitch_deg, a.heading_deg));
  const Eigen::Quaterniond qb(vehicle_to_map_rotation(b.roll_deg, b.pitch_deg, b.heading_deg));
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = qa.slerp(f, qb).toRotationMatrix();
  pose.translation() = Eigen::Vector3d((1 - f) * a.easting + f * b.easting,
                                       (1 - f) * a.northing + f * b.northing,
                                       -((1 - f) * a.depth_m + f * b.depth_m));
  NavSample s = nav_from_pose(pose, LocalOrigin{});
  s.time = time;
  return s;
}

}  // namespace bathyslam

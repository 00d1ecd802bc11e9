#include "core/pipeline/corrected_navigation.h"

#include <algorithm>
#include <span>

#include "core/submaps/joined_surveys.h"
#include "core/types/pose.h"

namespace bathyslam {

std::vector<NavSample> corrected_navigation(const Survey& survey, const PipelineResult& r, int survey_index) {
  const NodeRange own = survey_submaps(r.submaps, survey_index);
  const std::span<const Submap> submaps(r.submaps.submaps.data() + own.begin, static_cast<std::size_t>(own.size()));
  const LocalOrigin& origin = r.submaps.origin;
  // Correction of each submap: optimized pose relative to its DR pose, in the map frame.
  std::vector<Eigen::Isometry3d> corrections;
  for (int i = own.begin; i < own.end; ++i) corrections.push_back(r.optimized_poses[i] * r.dr_poses[i].inverse());
  auto correction_at = [&](double t) -> Eigen::Isometry3d {
    if (submaps.empty()) return Eigen::Isometry3d::Identity();
    if (t <= submaps.front().time_mid) return corrections.front();
    if (t >= submaps.back().time_mid) return corrections.back();
    const auto next = std::lower_bound(submaps.begin(), submaps.end(), t,
                                       [](const Submap& s, double time) { return s.time_mid < time; });
    const std::size_t b = static_cast<std::size_t>(next - submaps.begin()), a = b - 1;
    const double f = (t - submaps[a].time_mid) / (submaps[b].time_mid - submaps[a].time_mid);
    Eigen::Isometry3d c = Eigen::Isometry3d::Identity();
    c.linear() = Eigen::Quaterniond(corrections[a].rotation())
                     .slerp(f, Eigen::Quaterniond(corrections[b].rotation()))
                     .toRotationMatrix();
    c.translation() = (1 - f) * corrections[a].translation() + f * corrections[b].translation();
    return c;
  };
  std::vector<NavSample> out;
  out.reserve(survey.nav.size());
  for (const NavSample& s : survey.nav) {
    NavSample corrected = nav_from_pose(correction_at(s.time) * vehicle_pose(s, origin), origin);
    corrected.time = s.time;
    out.push_back(corrected);
  }
  return out;
}

}  // namespace bathyslam

#include "core/submaps/submap.h"

#include <algorithm>
#include <cmath>

#include "core/sync/nav_interpolation.h"

namespace bathyslam {
namespace {

struct PosedPing {
  std::size_t ping = 0;
  Eigen::Isometry3d pose;  // vehicle -> map, from the navigation at the ping's time
};

// sync: the navigation at every ping's time; pings outside the navigation are counted, not posed.
std::vector<PosedPing> sync_pings(const Survey& survey, const LocalOrigin& origin,
                                  std::size_t& dropped) {
  std::vector<PosedPing> posed;
  posed.reserve(survey.pings.size());
  for (std::size_t i = 0; i < survey.pings.size(); ++i) {
    const auto nav = interpolate_nav(survey.nav, survey.pings[i].time);
    if (!nav) {
      ++dropped;
      continue;
    }
    posed.push_back({i, vehicle_pose(*nav, origin)});
  }
  return posed;
}

int line_at(const std::vector<SurveyLine>& lines, const std::vector<NavSample>& nav, double time) {
  for (std::size_t l = 0; l < lines.size(); ++l) {
    if (time >= nav[lines[l].first].time && time <= nav[lines[l].last].time) return static_cast<int>(l);
  }
  return -1;
}

}  // namespace

LocalOrigin local_origin_of(const Survey& survey) {
  if (survey.nav.empty()) return {};
  return {std::round(survey.nav.front().easting / 100.0) * 100.0,
          std::round(survey.nav.front().northing / 100.0) * 100.0};
}

SubmapSet build_submaps(const Survey& survey, const SubmapConfig& config) {
  SubmapSet set;
  set.origin = local_origin_of(survey);
  set.lines = split_lines(survey.nav);
  const std::vector<PosedPing> posed = sync_pings(survey, set.origin, set.pings_dropped);

  const std::size_t n = static_cast<std::size_t>(config.pings_per_submap);
  for (std::size_t first = 0; first < posed.size(); first += n) {
    const std::size_t last = std::min(first + n, posed.size()) - 1;
    const PosedPing& mid = posed[(first + last) / 2];
    Submap submap;
    submap.index = static_cast<int>(set.submaps.size());
    submap.time_begin = survey.pings[posed[first].ping].time;
    submap.time_end = survey.pings[posed[last].ping].time;
    submap.time_mid = survey.pings[mid.ping].time;
    submap.line = line_at(set.lines, survey.nav, submap.time_mid);
    submap.dr_pose = mid.pose;
    if (survey.reference_nav) {
      if (const auto ref = interpolate_nav(*survey.reference_nav, submap.time_mid)) {
        submap.reference_pose = vehicle_pose(*ref, set.origin);
      }
    }
    // georef: beams -> map (by their ping's pose) -> submap frame.
    const Eigen::Isometry3d map_to_submap = submap.dr_pose.inverse();
    // Exactly as many as the beams: grown by doubling, a submap's points could take up to twice
    // the memory they use, and they are most of a survey's.
    std::size_t beams = 0;
    for (std::size_t k = first; k <= last; ++k) beams += survey.pings[posed[k].ping].beam_count;
    submap.points.reserve(beams);
    for (std::size_t k = first; k <= last; ++k) {
      const Eigen::Isometry3d ping_to_submap = map_to_submap * posed[k].pose;
      for (const Beam& b : survey.beams_of(survey.pings[posed[k].ping])) {
        submap.points.push_back((ping_to_submap * Eigen::Vector3d(b.along, b.across, b.down)).cast<float>());
      }
    }
    submap.extent = extent_of(submap.points);
    set.submaps.push_back(std::move(submap));
  }
  return set;
}

Eigen::AlignedBox2f extent_of(const std::vector<Eigen::Vector3f>& points) {
  Eigen::AlignedBox2f box;
  for (const Eigen::Vector3f& p : points) box.extend(p.head<2>());
  return box;
}

}  // namespace bathyslam

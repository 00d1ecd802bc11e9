#include "core/submaps/submap.h"

#include <algorithm>
#include <cmath>

#include "core/sync/nav_interpolation.h"

namespace bathyslam {
namespace {

int line_at(const std::vector<SurveyLine>& lines, const std::vector<NavSample>& nav, double time) {
  for (std::size_t l = 0; l < lines.size(); ++l) {
    if (time >= nav[lines[l].first].time && time <= nav[lines[l].last].time) return static_cast<int>(l);
  }
  return -1;
}

LocalOrigin local_origin_of(const std::vector<NavSample>& nav) {
  if (nav.empty()) return {};
  return {std::round(nav.front().easting / 100.0) * 100.0, std::round(nav.front().northing / 100.0) * 100.0};
}

}  // namespace

LocalOrigin local_origin_of(const Survey& survey) { return local_origin_of(survey.nav); }

SubmapBuilder::SubmapBuilder(std::vector<NavSample> nav, std::optional<std::vector<NavSample>> reference_nav,
                             const SubmapConfig& config)
    : nav_(std::move(nav)), reference_nav_(std::move(reference_nav)), config_(config) {
  set_.origin = local_origin_of(nav_);
}

// sync: the navigation at the ping's time; a ping outside the navigation is counted, not posed.
void SubmapBuilder::add_ping(double time, std::span<const Beam> beams) {
  const auto nav = interpolate_nav(nav_, time);
  if (!nav) {
    ++set_.pings_dropped;
    return;
  }
  swaths_.push_back(ping_swath(time, beams));
  pending_.push_back({time, vehicle_pose(*nav, set_.origin), pending_beams_.size(), beams.size()});
  pending_beams_.insert(pending_beams_.end(), beams.begin(), beams.end());
  if (pending_.size() == static_cast<std::size_t>(config_.pings_per_submap)) close_submap();
}

SubmapSet SubmapBuilder::finish() {
  if (!pending_.empty()) close_submap();
  // Lines once the footprint is known: their course window and shortest line follow it.
  set_.footprint = sounding_footprint(nav_, swaths_);
  set_.lines = split_lines(nav_, line_config_for(set_.footprint));
  for (Submap& submap : set_.submaps) submap.line = line_at(set_.lines, nav_, submap.time_mid);
  return std::move(set_);
}

void SubmapBuilder::close_submap() {
  const PendingPing& mid = pending_[(pending_.size() - 1) / 2];
  Submap submap;
  submap.index = static_cast<int>(set_.submaps.size());
  submap.time_begin = pending_.front().time;
  submap.time_end = pending_.back().time;
  submap.time_mid = mid.time;
  submap.dr_pose = mid.pose;
  if (reference_nav_) {
    if (const auto ref = interpolate_nav(*reference_nav_, submap.time_mid)) {
      submap.reference_pose = vehicle_pose(*ref, set_.origin);
    }
  }
  // georef: beams -> map (by their ping's pose) -> submap frame. Exactly as many points as
  // beams: grown by doubling, a submap's points could take up to twice the memory they use,
  // and they are most of a survey's.
  const Eigen::Isometry3d map_to_submap = submap.dr_pose.inverse();
  submap.points.reserve(pending_beams_.size());
  for (const PendingPing& ping : pending_) {
    const Eigen::Isometry3d ping_to_submap = map_to_submap * ping.pose;
    for (std::size_t b = ping.first_beam; b < ping.first_beam + ping.beam_count; ++b) {
      const Beam& beam = pending_beams_[b];
      submap.points.push_back((ping_to_submap * Eigen::Vector3d(beam.along, beam.across, beam.down)).cast<float>());
    }
  }
  submap.extent = extent_of(submap.points);
  set_.submaps.push_back(std::move(submap));
  pending_.clear();
  pending_beams_.clear();
}

LineConfig line_config_for(const SoundingFootprint& footprint) {
  LineConfig lines;
  lines.course_window_m *= length_scale(footprint);
  lines.min_length_m *= length_scale(footprint);
  return lines;
}

SubmapSet build_submaps(const Survey& survey, const SubmapConfig& config) {
  SubmapBuilder builder(survey.nav, survey.reference_nav, config);
  for (const Ping& ping : survey.pings) builder.add_ping(ping.time, survey.beams_of(ping));
  return builder.finish();
}

Eigen::AlignedBox2f extent_of(const std::vector<Eigen::Vector3f>& points) {
  Eigen::AlignedBox2f box;
  for (const Eigen::Vector3f& p : points) box.extend(p.head<2>());
  return box;
}

}  // namespace bathyslam

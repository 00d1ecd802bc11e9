#include "core/io/sonar_tracks.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/io/crs.h"

namespace bathyslam {
namespace {

// `to` - `from` in degrees, the short way round.
double turn_deg(double from, double to) {
  double d = std::fmod(to - from, 360.0);
  if (d > 180) d -= 360;
  if (d < -180) d += 360;
  return d;
}

double wrapped_deg(double deg, double half_turn_at) {
  if (deg > half_turn_at) deg -= 360;
  if (deg < half_turn_at - 360) deg += 360;
  return deg;
}

template <class T>
auto first_not_before(const std::vector<T>& v, double time) {
  return std::lower_bound(v.begin(), v.end(), time, [](const T& s, double t) { return s.time < t; });
}

}  // namespace

GeodeticTrack::GeodeticTrack(std::vector<GeodeticFix> fixes) : fixes_(std::move(fixes)) {
  std::stable_sort(fixes_.begin(), fixes_.end(), [](const GeodeticFix& a, const GeodeticFix& b) { return a.time < b.time; });
}

std::optional<std::pair<double, double>> GeodeticTrack::at(double time) const {
  if (fixes_.empty() || time < fixes_.front().time || time > fixes_.back().time) return std::nullopt;
  const auto after = first_not_before(fixes_, time);
  if (after->time == time || after == fixes_.begin()) return std::pair{after->latitude_deg, after->longitude_deg};
  const GeodeticFix& a = *(after - 1);
  const GeodeticFix& b = *after;
  const double w = (time - a.time) / (b.time - a.time);
  const double lon = wrapped_deg(a.longitude_deg + w * turn_deg(a.longitude_deg, b.longitude_deg), 180);
  return std::pair{a.latitude_deg + w * (b.latitude_deg - a.latitude_deg), lon};
}

FixProjection::FixProjection(std::string crs) : crs_(std::move(crs)) {}
FixProjection::~FixProjection() = default;

std::pair<double, double> FixProjection::forward(double latitude_deg, double longitude_deg, const std::string& where) {
  if (!projection_) {
    if (crs_.empty()) crs_ = utm_crs_of(longitude_deg, latitude_deg);
    if (const auto problem = crs_problem(crs_)) throw std::runtime_error(*problem);
    projection_ = std::make_unique<GeographicProjection>(crs_);
  }
  const auto en = projection_->forward(longitude_deg, latitude_deg);
  if (!std::isfinite(en.easting) || !std::isfinite(en.northing)) {
    throw std::runtime_error(where + ": cannot project the position into " + crs_);
  }
  return {en.easting, en.northing};
}

double AttitudeTrack::gap_at(double time) const {
  if (samples_.empty()) return INFINITY;
  const auto after = first_not_before(samples_, time);
  if (after == samples_.begin()) return after->time - time;
  if (after == samples_.end()) return time - samples_.back().time;
  return after->time - (after - 1)->time;
}

void AttitudeTrack::sort() {
  std::stable_sort(samples_.begin(), samples_.end(), [](const AttitudeSample& a, const AttitudeSample& b) { return a.time < b.time; });
}

AttitudeSample AttitudeTrack::at(double time) const {
  if (samples_.empty()) return {time};
  const auto after = first_not_before(samples_, time);
  if (after == samples_.begin()) return *after;
  if (after == samples_.end()) return samples_.back();
  const AttitudeSample& a = *(after - 1);
  const AttitudeSample& b = *after;
  const double w = b.time > a.time ? (time - a.time) / (b.time - a.time) : 0.0;
  const auto mix = [w](double x, double y) { return x + w * (y - x); };
  return {time, mix(a.roll_deg, b.roll_deg), mix(a.pitch_deg, b.pitch_deg), mix(a.heave_m, b.heave_m),
          wrapped_deg(a.heading_deg + w * turn_deg(a.heading_deg, b.heading_deg), 360)};
}

}  // namespace bathyslam

#pragma once
// The navigation a sonar file records beside its pings, as time series read at a ping's time:
// the position fixes of the positioning system the survey uses, and the motion sensor's attitude.
// Shared by the raw-format readers (Kongsberg .all, XTF).
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace bathyslam {

struct GeodeticFix {
  double time = 0;  // seconds since the epoch
  double latitude_deg = 0, longitude_deg = 0;
};

// Position fixes interpolated linearly in latitude and longitude (across the antimeridian the
// short way); nothing outside their span: a ping there is counted, not extrapolated.
class GeodeticTrack {
 public:
  explicit GeodeticTrack(std::vector<GeodeticFix> fixes);
  std::size_t size() const { return fixes_.size(); }
  // Latitude and longitude at `time`.
  std::optional<std::pair<double, double>> at(double time) const;

 private:
  std::vector<GeodeticFix> fixes_;
};

struct AttitudeSample {
  double time = 0;
  double roll_deg = 0, pitch_deg = 0, heave_m = 0, heading_deg = 0;
};

// Motion-sensor samples interpolated at a time (heading the short way round); outside their span
// the nearest sample, without any all zero.
class AttitudeTrack {
 public:
  void add(const AttitudeSample& sample) { samples_.push_back(sample); }
  void sort();  // after the last add
  std::size_t size() const { return samples_.size(); }
  AttitudeSample at(double time) const;
  // How far `time` is from the samples that give at(time): the span of the two around it, or the
  // distance to the nearest outside their span; infinite without any.
  double gap_at(double time) const;

 private:
  std::vector<AttitudeSample> samples_;
};

class GeographicProjection;

// Fixes projected into the survey's CRS: the one asked for, or the WGS 84 UTM zone of the first fix.
class FixProjection {
 public:
  explicit FixProjection(std::string crs);
  ~FixProjection();
  // Easting and northing of a fix; the first call settles the CRS. Throws std::runtime_error for
  // an unusable CRS, or naming `where` for a fix that does not project.
  std::pair<double, double> forward(double latitude_deg, double longitude_deg, const std::string& where);
  const std::string& crs() const { return crs_; }

 private:
  std::string crs_;
  std::unique_ptr<GeographicProjection> projection_;
};

}  // namespace bathyslam

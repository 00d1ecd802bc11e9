#pragma once
// Submaps (docs/design.md pipeline: sync, georef, submaps): pings posed by the navigation interpolated
// at their times, grouped N at a time; each submap's frame is the vehicle pose at its middle
// ping, and its soundings are stored in that frame (centred, so floats keep millimetres).
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>

#include "core/lines/survey_lines.h"
#include "core/submaps/sounding_footprint.h"
#include "core/types/pose.h"
#include "core/types/survey.h"

namespace bathyslam {

struct SubmapConfig {
  int pings_per_submap = 100;  // Table 1 (a)
  template <typename Field>
  void fields(Field&& field) {
    field("pings_per_submap", pings_per_submap, 10, 10000);
  }
};

struct Submap {
  int index = 0;
  int line = -1;  // index into the survey's lines; -1 for a submap taken in a turn
  double time_begin = 0, time_mid = 0, time_end = 0;
  Eigen::Isometry3d dr_pose = Eigen::Isometry3d::Identity();  // submap frame -> map frame (DR)
  std::optional<Eigen::Isometry3d> reference_pose;            // the same from reference_nav
  std::vector<Eigen::Vector3f> points;                        // soundings, submap frame
  // The rectangle `points` span horizontally (submap frame), kept by build_submaps so that the
  // footprints of every batch's candidate search need not scan the points again; empty on a
  // submap built by hand (footprint_of then scans them).
  Eigen::AlignedBox2f extent;

  // A growing vector<Submap> must move its submaps, not copy their soundings (on `lake` the
  // copies were 3 % of the run's CPU, in the serial read): AlignedBox's move is not noexcept, so
  // the implicit one would not be either.
  Submap() = default;
  Submap(const Submap&) = default;
  Submap& operator=(const Submap&) = default;
  Submap(Submap&&) noexcept = default;
  Submap& operator=(Submap&&) noexcept = default;
};
static_assert(std::is_nothrow_move_constructible_v<Submap>);

// The rectangle `points` span horizontally (empty for no points).
Eigen::AlignedBox2f extent_of(const std::vector<Eigen::Vector3f>& points);

struct SubmapSet {
  LocalOrigin origin;              // map frame = projected CRS minus this
  std::vector<SurveyLine> lines;
  std::vector<Submap> submaps;
  std::size_t pings_dropped = 0;   // outside the navigation's time span (sync)
  SoundingFootprint footprint;     // of every ping given to the builder; 0 for submaps made by hand
  // Several surveys of one site (join_surveys): the first submap of each survey after the first.
  std::vector<int> survey_starts;
};

// How to split a survey of this footprint into lines: the lake's course window and shortest line
// scaled as the core's lengths are (length_scale), since a survey flown higher turns wider and its
// navigation wanders further within a window (at 1500 m, the lake's 10 m window split six lines
// into 71).
LineConfig line_config_for(const SoundingFootprint& footprint);

// The map frame's origin for a survey: its first navigation sample, rounded to 100 m.
LocalOrigin local_origin_of(const Survey& survey);

// Submaps built one ping at a time, in time order, so that a reader streaming the pings holds
// no more than one submap's beams (`large`'s beams and points together were 4.5 GB).
class SubmapBuilder {
 public:
  SubmapBuilder(std::vector<NavSample> nav, std::optional<std::vector<NavSample>> reference_nav,
                const SubmapConfig& config = {});
  void add_ping(double time, std::span<const Beam> beams);
  SubmapSet finish();  // the builder is spent

 private:
  struct PendingPing {
    double time = 0;
    Eigen::Isometry3d pose;  // vehicle -> map, from the navigation at the ping's time
    std::size_t first_beam = 0, beam_count = 0;  // in pending_beams_
  };
  void close_submap();

  std::vector<NavSample> nav_;
  std::optional<std::vector<NavSample>> reference_nav_;
  SubmapConfig config_;
  SubmapSet set_;
  std::vector<PendingPing> pending_;  // posed pings of the submap being gathered
  std::vector<Beam> pending_beams_;
  std::vector<PingSwath> swaths_;  // every ping's, for the footprint
};

SubmapSet build_submaps(const Survey& survey, const SubmapConfig& config = {});

}  // namespace bathyslam

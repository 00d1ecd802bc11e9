// bench_gsf_losses BUNDLE OUT_PREFIX: writes copies of a bundle that each carry one of the
// losses a GSF round trip imposes (docs/formats.md, "GSF out"), so that `bathyslam process` on each
// shows which loss moves the trajectory error:
//
//   OUT_PREFIX.pingnav    navigation only at the ping times (interpolated, not rounded)
//   OUT_PREFIX.position   easting/northing through WGS 84 latitude/longitude rounded to 1e-7 deg
//   OUT_PREFIX.attitude   roll, pitch, heading rounded to 0.01 deg, soundings left in place
//   OUT_PREFIX.vdepth     vehicle depth rounded to 1 cm, the beams moving with the vehicle
//   OUT_PREFIX.beams      beam offsets rounded to STEP in GSF's level, heading-aligned frame
//   OUT_PREFIX.all        all of the above together: GSF's losses without GSF
//   OUT_PREFIX.ditherK    (K = 1..3) the beams with uniform noise of +-STEP/2 in the level frame:
//                         a perturbation of the size of the beams' rounding, not the rounding
//
// STEP is the beam arrays' resolution (--step, 0.001 m: the writer's millimetres). With
// --dither-only, only the ditherK copies: the noise floor of a figure (docs/performance.md).
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "core/io/bundle.h"
#include "core/io/crs.h"
#include "core/sync/nav_interpolation.h"
#include "core/types/pose.h"

namespace {

using namespace bathyslam;

double rounded(double value, double step) { return std::round(value / step) * step; }

// The navigation interpolated at every distinct ping time: what a GSF file carries.
std::vector<NavSample> nav_at_pings(const Survey& survey) {
  std::vector<NavSample> nav;
  for (const Ping& ping : survey.pings) {
    if (!nav.empty() && ping.time <= nav.back().time) continue;
    if (auto at = interpolate_nav(survey.nav, ping.time)) nav.push_back(*at);
  }
  return nav;
}

void round_positions(std::vector<NavSample>& nav, const std::string& crs) {
  const GeographicProjection projection(crs);
  for (NavSample& s : nav) {
    const auto ll = projection.inverse(s.easting, s.northing);
    const auto en = projection.forward(rounded(ll.longitude_deg, 1e-7), rounded(ll.latitude_deg, 1e-7));
    s.easting = en.easting;
    s.northing = en.northing;
  }
}

void round_attitude(std::vector<NavSample>& nav) {
  for (NavSample& s : nav) {
    s.roll_deg = rounded(s.roll_deg, 0.01);
    s.pitch_deg = rounded(s.pitch_deg, 0.01);
    s.heading_deg = std::fmod(rounded(s.heading_deg, 0.01) + 360.0, 360.0);
  }
}

void round_depth(std::vector<NavSample>& nav) {
  for (NavSample& s : nav) s.depth_m = rounded(s.depth_m, 0.01);
}

// Re-expresses every beam for the navigation `to` so that it lands where `from` put it.
void keep_soundings(Survey& survey, const std::vector<NavSample>& from, const std::vector<NavSample>& to) {
  for (const Ping& ping : survey.pings) {
    const auto a = interpolate_nav(from, ping.time), b = interpolate_nav(to, ping.time);
    if (!a || !b) continue;
    const Eigen::Isometry3d change = vehicle_pose(*b, {}).inverse() * vehicle_pose(*a, {});
    for (std::uint32_t k = ping.first_beam; k < ping.first_beam + ping.beam_count; ++k) {
      Beam& beam = survey.beams[k];
      const Eigen::Vector3d v = change * Eigen::Vector3d(beam.along, beam.across, beam.down);
      beam.along = static_cast<float>(v.x());
      beam.across = static_cast<float>(v.y());
      beam.down = static_cast<float>(v.z());
    }
  }
}

// Applies `change` to every beam in GSF's level, heading-aligned frame (the vehicle's roll and
// pitch at the ping taken out), then puts roll and pitch back.
template <typename Change>
void change_in_level_frame(Survey& survey, Change change) {
  for (const Ping& ping : survey.pings) {
    const auto at = interpolate_nav(survey.nav, ping.time);
    if (!at) continue;
    const Eigen::Matrix3d heading = vehicle_to_map_rotation(0, 0, at->heading_deg);
    const Eigen::Matrix3d tilt = heading.transpose() * vehicle_to_map_rotation(at->roll_deg, at->pitch_deg, at->heading_deg);
    for (std::uint32_t k = ping.first_beam; k < ping.first_beam + ping.beam_count; ++k) {
      Beam& beam = survey.beams[k];
      Eigen::Vector3d level = tilt * Eigen::Vector3d(beam.along, beam.across, beam.down);
      for (int i = 0; i < 3; ++i) level[i] = change(level[i]);
      const Eigen::Vector3d v = tilt.transpose() * level;
      beam.along = static_cast<float>(v.x());
      beam.across = static_cast<float>(v.y());
      beam.down = static_cast<float>(v.z());
    }
  }
}

void write(const Survey& survey, const std::string& path) {
  write_bundle(survey, path);
  std::printf("%s\n", path.c_str());
}

int write_dithers(const Survey& original, const std::string& prefix, double step) {
  for (int k = 1; k <= 3; ++k) {
    std::mt19937_64 random(k);
    std::uniform_real_distribution<double> noise(-step / 2, step / 2);
    Survey s = original;
    change_in_level_frame(s, [&](double v) { return v + noise(random); });
    write(s, prefix + ".dither" + std::to_string(k));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_gsf_losses BUNDLE OUT_PREFIX [--step 0.001] [--dither-only]\n");
    return 2;
  }
  const std::string prefix = argv[2];
  double step = 0.001;
  bool dither_only = false;
  for (int i = 3; i < argc; ++i) {
    const std::string option = argv[i];
    if (option == "--step" && i + 1 < argc) {
      step = std::stod(argv[++i]);
    } else if (option == "--dither-only") {
      dither_only = true;
    } else {
      std::fprintf(stderr, "bench_gsf_losses: unknown option %s\n", option.c_str());
      return 2;
    }
  }
  const Survey original = load_bundle(argv[1]);
  const std::string& crs = original.metadata.crs;

  if (dither_only) return write_dithers(original, prefix, step);

  Survey s = original;
  s.nav = nav_at_pings(original);
  write(s, prefix + ".pingnav");

  s = original;
  round_positions(s.nav, crs);
  write(s, prefix + ".position");

  s = original;
  round_attitude(s.nav);
  keep_soundings(s, original.nav, s.nav);
  write(s, prefix + ".attitude");

  s = original;
  round_depth(s.nav);
  write(s, prefix + ".vdepth");

  s = original;
  change_in_level_frame(s, [step](double v) { return rounded(v, step); });
  write(s, prefix + ".beams");

  s = original;
  change_in_level_frame(s, [step](double v) { return rounded(v, step); });
  s.nav = nav_at_pings(s);
  round_attitude(s.nav);
  keep_soundings(s, nav_at_pings(original), s.nav);
  round_positions(s.nav, crs);
  round_depth(s.nav);
  write(s, prefix + ".all");

  return write_dithers(original, prefix, step);
}

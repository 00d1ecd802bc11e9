#include "core/fuse/soundings_csv.h"

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

namespace bathyslam {

std::uint64_t write_soundings_csv(const SubmapSet& set, std::span<const Eigen::Isometry3d> poses,
                                  const std::filesystem::path& path) {
  if (poses.size() != set.submaps.size()) {
    throw std::invalid_argument("write_soundings_csv: " + std::to_string(poses.size()) + " poses for " +
                                std::to_string(set.submaps.size()) + " submaps");
  }
  const std::filesystem::path partial = path.string() + ".partial";
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> out(std::fopen(partial.c_str(), "w"), &std::fclose);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  std::setvbuf(out.get(), nullptr, _IOFBF, 1 << 20);
  std::fprintf(out.get(), "%s\n", kSoundingsHeader);
  std::uint64_t written = 0;
  for (std::size_t i = 0; i < set.submaps.size(); ++i) {
    const Submap& submap = set.submaps[i];
    // Into CRS coordinates: the map frame plus the survey's local origin.
    Eigen::Isometry3d to_crs = poses[i];
    to_crs.translation() += Eigen::Vector3d(set.origin.easting, set.origin.northing, 0);
    for (const Eigen::Vector3f& p : submap.points) {
      const Eigen::Vector3d q = to_crs * p.cast<double>();
      std::fprintf(out.get(), "%.3f,%.3f,%.3f,%d,%d\n", q.x(), q.y(), q.z(), submap.line, submap.index);
    }
    written += submap.points.size();
  }
  if (std::fflush(out.get()) != 0 || std::ferror(out.get())) throw std::runtime_error(path.string() + ": write failed");
  out.reset();
  std::filesystem::rename(partial, path);
  return written;
}

}  // namespace bathyslam

// What `bathyslam process --export-gsf --export-soundings` hands a hydrographer: the pings with
// the corrected navigation, which must put every sounding where the fused map has it, and the
// corrected soundings themselves.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include "core/fuse/fuse.h"
#include "core/fuse/soundings_csv.h"
#include "core/io/bundle.h"
#include "core/io/gsf/gsf_survey.h"
#include "core/io/gsf/navigation_rewrite.h"
#include "core/pipeline/corrected_navigation.h"
#include "core/pipeline/pipeline.h"
#include "core/products/corrected_gsf.h"
#include "core/sim/simulator.h"

namespace bathyslam {
namespace {

namespace fs = std::filesystem;

struct CellDifferences {
  std::size_t cells = 0;
  double rms_m = 0, max_m = 0;
};

// Elevation differences over the cells both maps have (both sit on the CRS-anchored lattice).
CellDifferences compare(const GridRaster& a, const GridRaster& b) {
  CellDifferences d;
  double sum2 = 0;
  const GridGeometry& ga = a.geometry;
  for (int y = 0; y < ga.height; ++y) {
    for (int x = 0; x < ga.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * ga.width + x;
      const std::int64_t col = ga.left + x, row = ga.top - y;
      if (!a.valid(i) || !b.geometry.contains(col, row)) continue;
      const std::size_t j = b.geometry.index(col, row);
      if (!b.valid(j)) continue;
      const double e = static_cast<double>(a.elevation[i]) - b.elevation[j];
      sum2 += e * e;
      d.max_m = std::max(d.max_m, std::abs(e));
      ++d.cells;
    }
  }
  d.rms_m = d.cells > 0 ? std::sqrt(sum2 / d.cells) : 0;
  return d;
}

class GsfExport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::SimulationConfig config;  // small, seed 1, the paper's drift
    simulation_ = new sim::Simulation(sim::simulate(config));
    PipelineConfig pipeline = preset_config(Configuration::kGicp);
    pipeline.threads = 1;
    result_ = new PipelineResult(run_pipeline(simulation_->survey, pipeline));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete simulation_;
  }
  // A corrected GSF file read back and fused with its own navigation, no SLAM, must give the
  // SLAM map back: cell differences within the sounding noise, far below dead reckoning's.
  static void expect_slam_map_from(const fs::path& corrected_gsf, const char* what) {
    const Survey corrected = gsf::read_survey({corrected_gsf}).survey;
    const FuseConfig fuse;
    const GridRaster slam_map = fuse_submaps(result_->submaps, result_->optimized_poses, fuse);
    const SubmapSet corrected_submaps = build_submaps(corrected);
    std::vector<Eigen::Isometry3d> poses;
    for (const Submap& s : corrected_submaps.submaps) poses.push_back(s.dr_pose);
    const GridRaster gsf_map = fuse_submaps(corrected_submaps, poses, fuse);
    const GridRaster dr_map = fuse_submaps(result_->submaps, result_->dr_poses, fuse);

    const CellDifferences d = compare(slam_map, gsf_map);
    const CellDifferences before = compare(slam_map, dr_map);
    ASSERT_GT(d.cells, slam_map.valid_cells() * 9 / 10);
    // Sounding noise at 10 m: 0.05 m + 0.2 % of depth = 0.07 m.
    EXPECT_LT(d.rms_m, 0.07) << "max " << d.max_m << " m over " << d.cells << " cells";
    EXPECT_GT(before.rms_m, 2 * d.rms_m) << "dead reckoning rms " << before.rms_m;
    std::printf("%s vs SLAM map: rms %.4f m, max %.3f m over %zu cells (dead reckoning: rms %.4f m)\n", what,
                d.rms_m, d.max_m, d.cells, before.rms_m);
  }
  static fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("bathyslam_gsf_export_" + name); }

  static sim::Simulation* simulation_;
  static PipelineResult* result_;
};
sim::Simulation* GsfExport::simulation_ = nullptr;
PipelineResult* GsfExport::result_ = nullptr;


TEST_F(GsfExport, CorrectedGsfPlacesSoundingsWhereTheFusedMapHasThem) {
  const Survey& survey = simulation_->survey;
  const fs::path path = temp("corrected.gsf");
  gsf::write_survey(survey, corrected_navigation(survey, *result_), path);
  expect_slam_map_from(path, "corrected.gsf");
  fs::remove(path);
}

// `process` reads a bundle without holding its soundings, and writes the corrected GSF by
// streaming the bundle again: the same file as from the survey held whole.
TEST_F(GsfExport, ACorrectedGsfStreamedFromTheBundleIsTheSameFile) {
  const Survey& survey = simulation_->survey;
  const fs::path bundle = temp("bundle"), whole = temp("whole.gsf"), streamed = temp("streamed.gsf");
  write_bundle(survey, bundle);
  Survey without_soundings = survey;
  without_soundings.pings.clear();
  without_soundings.beams.clear();
  const std::uint64_t n_whole = gsf::write_survey(survey, corrected_navigation(survey, *result_), whole);
  const std::uint64_t n_streamed = write_corrected_gsf(without_soundings, *result_, streamed,
                                                       [&](PingSink& sink) { return stream_bundle(bundle, sink); });
  EXPECT_EQ(n_whole, survey.pings.size());
  EXPECT_EQ(n_streamed, n_whole);
  auto bytes = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  EXPECT_GT(bytes(whole).size(), 1000000u);
  EXPECT_TRUE(bytes(whole) == bytes(streamed)) << "the files differ";
  fs::remove_all(bundle);
  fs::remove(whole);
  fs::remove(streamed);
}

// GSF in, GSF out: the survey as a GSF file with dead reckoning, then that file with the
// corrected navigation in its ping headers (depths untouched).
TEST_F(GsfExport, RewrittenGsfPlacesSoundingsWhereTheFusedMapHasThem) {
  const Survey& survey = simulation_->survey;
  const fs::path dr = temp("dr.gsf"), corrected = temp("dr.corrected.gsf");
  gsf::write_survey(survey, survey.nav, dr);
  const gsf::RewriteCount n = gsf::rewrite_navigation(dr, corrected, corrected_navigation(survey, *result_),
                                                      survey.metadata.crs);
  EXPECT_EQ(n.rewritten, survey.pings.size());
  expect_slam_map_from(corrected, "dr.corrected.gsf");
  fs::remove(dr);
  fs::remove(corrected);
}

TEST_F(GsfExport, SoundingsCsvHoldsEveryCorrectedSoundingInCrsCoordinates) {
  const fs::path path = temp("soundings.csv");
  const std::uint64_t n = write_soundings_csv(result_->submaps, result_->optimized_poses, path);
  std::size_t expected = 0;
  for (const Submap& s : result_->submaps.submaps) expected += s.points.size();
  EXPECT_EQ(n, expected);

  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, kSoundingsHeader);
  // The first sounding of the last submap, placed by hand, must be on its row.
  const Submap& last = result_->submaps.submaps.back();
  const Eigen::Vector3d p = result_->optimized_poses.back() * last.points.front().cast<double>();
  std::size_t rows = 0;
  std::string last_first;
  for (; std::getline(in, line); ++rows) {
    if (rows == n - last.points.size()) last_first = line;
  }
  fs::remove(path);
  EXPECT_EQ(rows, n);
  double e = 0, north = 0, z = 0;
  int line_index = 0, submap = 0;
  ASSERT_EQ(std::sscanf(last_first.c_str(), "%lf,%lf,%lf,%d,%d", &e, &north, &z, &line_index, &submap), 5) << last_first;
  EXPECT_NEAR(e, p.x() + result_->submaps.origin.easting, 0.001);
  EXPECT_NEAR(north, p.y() + result_->submaps.origin.northing, 0.001);
  EXPECT_NEAR(z, p.z(), 0.001);
  EXPECT_EQ(line_index, last.line);
  EXPECT_EQ(submap, last.index);
}

}  // namespace
}  // namespace bathyslam

// How well a site's difference map finds what changed: the cells of difference_<a>_<b>.tif against
// the simulator's truth: the changes the later epoch's survey.json lists (site.h), or where its sand
// waves migrated, truth_change.tif beside it (every change since epoch 1 sampled on a grid). Of the cells that
// truly changed by more than a threshold, the share flagged significant; of the cells that did not
// change at all (at their centre and corners), the share flagged.
//
//   bench_change_detection OUT/difference_1_2.tif EPOCH2/survey.json [threshold_m = 0.3]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gdal_priv.h>
#include <nlohmann/json.hpp>

#include "core/sim/site.h"

using namespace bathyslam::sim;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s difference.tif survey.json [threshold_m]\n", argv[0]);
    return 2;
  }
  const double threshold = argc > 3 ? std::stod(argv[3]) : 0.3;
  const nlohmann::json site = nlohmann::json::parse(std::ifstream(argv[2]))["vehicle"]["simulation"]["site"];
  std::vector<SeabedChange> changes;
  for (const auto& c : site["changes_since_epoch_1"]) changes.push_back(seabed_change_from_json(c));
  const double east0 = site["local_origin"]["easting"], north0 = site["local_origin"]["northing"];
  GDALAllRegister();
  const std::filesystem::path truth_tif = std::filesystem::path(argv[2]).parent_path() / "truth_change.tif";
  std::vector<float> truth_cells;
  double tgt[6] = {0, 1, 0, 0, 0, -1};
  int tw = 0, th = 0;
  GDALDataset* t = site.contains("sand_waves_migrated_m") ? GDALDataset::Open(truth_tif.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY)
                                                         : nullptr;
  if (site.contains("sand_waves_migrated_m") && !t) {
    std::fprintf(stderr, "%s: the sand waves migrated and there is no truth_change.tif beside it\n", argv[2]);
    return 1;
  }
  if (t) {
    tw = t->GetRasterXSize(), th = t->GetRasterYSize();
    t->GetGeoTransform(tgt);
    truth_cells.resize(static_cast<std::size_t>(tw) * th);
    if (t->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, tw, th, truth_cells.data(), tw, th, GDT_Float32, 0, 0) != CE_None) {
      std::fprintf(stderr, "%s: cannot read\n", truth_tif.c_str());
      return 1;
    }
    GDALClose(t);
    std::printf("truth: %s\n", truth_tif.c_str());
  }
  const auto truth = [&](double e, double n) {
    if (!truth_cells.empty()) {
      const auto x = static_cast<long>(std::floor((e - tgt[0]) / tgt[1])), y = static_cast<long>(std::floor((n - tgt[3]) / tgt[5]));
      if (x < 0 || y < 0 || x >= tw || y >= th) return 0.0;
      const double t = truth_cells[static_cast<std::size_t>(y) * tw + x];
      return std::abs(t) < 1e-4 ? 0.0 : t;  // float rounding of two equal elevations
    }
    double sum = 0;
    for (const SeabedChange& c : changes) sum += elevation_change(c, e - east0, n - north0);
    return sum;
  };

  GDALDataset* ds = GDALDataset::Open(argv[1], GDAL_OF_RASTER | GDAL_OF_READONLY);
  if (!ds) {
    std::fprintf(stderr, "%s: cannot open\n", argv[1]);
    return 1;
  }
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  double gt[6];
  ds->GetGeoTransform(gt);
  std::vector<float> change(static_cast<std::size_t>(w) * h), significant(change.size());
  if (ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, w, h, change.data(), w, h, GDT_Float32, 0, 0) != CE_None ||
      ds->GetRasterBand(3)->RasterIO(GF_Read, 0, 0, w, h, significant.data(), w, h, GDT_Float32, 0, 0) != CE_None) {
    std::fprintf(stderr, "%s: cannot read bands 1 and 3\n", argv[1]);
    return 1;
  }
  GDALClose(ds);

  std::size_t changed = 0, changed_found = 0, unchanged = 0, unchanged_flagged = 0, small = 0, small_flagged = 0;
  double error2 = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (std::isnan(change[i])) continue;
      const double e = gt[0] + (x + 0.5) * gt[1], n = gt[3] + (y + 0.5) * gt[5];
      const double t = truth(e, n);
      const double half = 0.5 * gt[1];
      const bool untouched = t == 0 && truth(e - half, n - half) == 0 && truth(e + half, n - half) == 0 &&
                             truth(e - half, n + half) == 0 && truth(e + half, n + half) == 0;
      if (std::abs(t) < 0.05) {  // where every cell changed a little (migrating sand waves)
        ++small;
        small_flagged += significant[i] == 1.0f;
      }
      if (std::abs(t) > threshold) {
        ++changed;
        changed_found += significant[i] == 1.0f;
      } else if (untouched) {
        ++unchanged;
        unchanged_flagged += significant[i] == 1.0f;
        error2 += change[i] * change[i];
      }
    }
  }
  std::printf("changed by more than %.2f m: %zu cells, %zu flagged (%.1f %%)\n", threshold, changed, changed_found,
              changed ? 100.0 * changed_found / changed : 0.0);
  std::printf("unchanged: %zu cells, %zu flagged (%.2f %%), their change rmse %.3f m\n", unchanged, unchanged_flagged,
              unchanged ? 100.0 * unchanged_flagged / unchanged : 0.0, unchanged ? std::sqrt(error2 / unchanged) : 0.0);
  std::printf("changed by less than 0.05 m: %zu cells, %zu flagged (%.2f %%)\n", small, small_flagged,
              small ? 100.0 * small_flagged / small : 0.0);
  return 0;
}

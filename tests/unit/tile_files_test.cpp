// What the writers put on disk, read back with GDAL, OpenVDB and OpenCV.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <string>

#include <csignal>
#include <functional>
#include <sys/resource.h>
#include <unistd.h>

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <opencv2/imgcodecs.hpp>
#include <openvdb/openvdb.h>

#include "core/io/file_bytes.h"
#include "core/tiles/bag_writer.h"
#include "core/tiles/geotiff_writer.h"
#include "core/tiles/quicklook.h"
#include "core/tiles/tile_files.h"
#include "core/tiles/vdb_writer.h"

namespace bathyslam {
namespace {

namespace fs = std::filesystem;

class TileFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("bathyslam_tile_files_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    GDALAllRegister();
    openvdb::initialize();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // 600 × 300 cells at 0.5 m in UTM 51N (more than one 512 block, so the COG has an overview),
  // a slope from west to east, a hole of NoData, and uncertainty NaN where a cell has one sounding.
  static GridRaster sample_map() {
    GridGeometry g{0.5, 904100, 9260299, 600, 300};
    GridRaster r = GridRaster::no_data(g);
    for (int y = 0; y < g.height; ++y) {
      for (int x = 0; x < g.width; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
        if (x >= 100 && x < 120 && y >= 50 && y < 60) continue;  // the hole
        r.elevation[i] = -12.0f + 0.01f * x;
        r.count[i] = static_cast<float>(1 + (x + y) % 7);
        r.uncertainty[i] = r.count[i] > 1 ? 0.05f + 0.001f * y : NAN;
      }
    }
    return r;
  }

  fs::path dir_;
};

TEST_F(TileFiles, BagReadsBackWithCrsGeotransformValuesNoDataAndMetadata) {
  const GridRaster map = sample_map();
  const fs::path path = dir_ / "map.bag";
  write_bag(map, "EPSG:32651", {"test grid", "fused by the test", "bathyslam"}, path);

  GDALDataset* ds = GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  ASSERT_NE(ds, nullptr);
  EXPECT_STREQ(ds->GetDriver()->GetDescription(), "BAG");
  EXPECT_EQ(ds->GetRasterXSize(), 600);
  EXPECT_EQ(ds->GetRasterYSize(), 300);
  ASSERT_EQ(ds->GetRasterCount(), 2);
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  ASSERT_NE(srs, nullptr);
  OGRSpatialReference utm51n;
  utm51n.importFromEPSG(32651);
  EXPECT_TRUE(srs->IsProjected());
  EXPECT_TRUE(srs->IsSameGeogCS(&utm51n));
  EXPECT_EQ(srs->GetUTMZone(), 51);

  std::array<double, 6> t{};
  ASSERT_EQ(ds->GetGeoTransform(t.data()), CE_None);
  // The same cell edges as the GeoTIFF (BAG stores cell centres; GDAL gives back the edges).
  EXPECT_NEAR(t[0], 452050.0, 1e-6);
  EXPECT_NEAR(t[3], 4630150.0, 1e-6);
  EXPECT_DOUBLE_EQ(t[1], 0.5);
  EXPECT_DOUBLE_EQ(t[5], -0.5);

  const char* names[] = {"elevation", "uncertainty"};
  for (int b = 1; b <= 2; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    EXPECT_STREQ(band->GetDescription(), names[b - 1]);
    int has_nodata = 0;
    EXPECT_FLOAT_EQ(static_cast<float>(band->GetNoDataValue(&has_nodata)), kBagNoData);
    EXPECT_TRUE(has_nodata);
  }
  auto read = [&](int band, int x, int y) {
    float v = 0;
    EXPECT_EQ(ds->GetRasterBand(band)->RasterIO(GF_Read, x, y, 1, 1, &v, 1, 1, GDT_Float32, 0, 0, nullptr), CE_None);
    return v;
  };
  for (const auto& [x, y] : std::array<std::pair<int, int>, 5>{{{0, 0}, {599, 299}, {250, 17}, {7, 200}, {110, 55}}}) {
    const std::size_t i = static_cast<std::size_t>(y) * 600 + x;
    const float elevation = read(1, x, y), uncertainty = read(2, x, y);
    if (std::isnan(map.elevation[i])) EXPECT_EQ(elevation, kBagNoData) << x << "," << y;
    else EXPECT_FLOAT_EQ(elevation, map.elevation[i]) << x << "," << y;
    if (std::isnan(map.uncertainty[i])) EXPECT_EQ(uncertainty, kBagNoData) << x << "," << y;
    else EXPECT_FLOAT_EQ(uncertainty, map.uncertainty[i]) << x << "," << y;
  }
  char** xml = ds->GetMetadata("xml:BAG");
  ASSERT_NE(xml, nullptr);
  const std::string metadata = xml[0];
  EXPECT_NE(metadata.find("test grid"), std::string::npos);
  EXPECT_NE(metadata.find("rawStdDev"), std::string::npos);
  GDALClose(ds);
}

TEST_F(TileFiles, GeoTiffReadsBackWithCrsGeotransformValuesNoDataAndCogLayout) {
  const GridRaster map = sample_map();
  const fs::path path = dir_ / "map.tif";
  write_geotiff(map, "EPSG:32651", path);

  GDALDataset* ds = GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  ASSERT_NE(ds, nullptr);
  EXPECT_EQ(ds->GetRasterXSize(), 600);
  EXPECT_EQ(ds->GetRasterYSize(), 300);
  ASSERT_EQ(ds->GetRasterCount(), 3);
  const OGRSpatialReference* srs = ds->GetSpatialRef();
  ASSERT_NE(srs, nullptr);
  EXPECT_STREQ(srs->GetAuthorityName(nullptr), "EPSG");
  EXPECT_STREQ(srs->GetAuthorityCode(nullptr), "32651");

  std::array<double, 6> t{};
  ASSERT_EQ(ds->GetGeoTransform(t.data()), CE_None);
  // Upper-left corner: column 904100 × 0.5 m, top of row 9260299; lower-right 600 × 300 cells on.
  EXPECT_DOUBLE_EQ(t[0], 452050.0);
  EXPECT_DOUBLE_EQ(t[3], 4630150.0);
  EXPECT_DOUBLE_EQ(t[1], 0.5);
  EXPECT_DOUBLE_EQ(t[5], -0.5);
  EXPECT_EQ(t[2], 0.0);
  EXPECT_EQ(t[4], 0.0);
  EXPECT_DOUBLE_EQ(t[0] + 600 * t[1], 452350.0);
  EXPECT_DOUBLE_EQ(t[3] + 300 * t[5], 4630000.0);

  EXPECT_STREQ(ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE"), "COG");
  EXPECT_STREQ(ds->GetMetadataItem("COMPRESSION", "IMAGE_STRUCTURE"), "ZSTD");
  EXPECT_STREQ(ds->GetMetadataItem("PREDICTOR", "IMAGE_STRUCTURE"), "3") << "floating-point predictor";
  const char* names[] = {"elevation", "uncertainty", "count"};
  for (int b = 1; b <= 3; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b);
    EXPECT_EQ(band->GetRasterDataType(), GDT_Float32);
    EXPECT_STREQ(band->GetDescription(), names[b - 1]);
    int has_nodata = 0;
    EXPECT_TRUE(std::isnan(band->GetNoDataValue(&has_nodata)));
    EXPECT_TRUE(has_nodata);
    int bx = 0, by = 0;
    band->GetBlockSize(&bx, &by);
    EXPECT_EQ(bx, 512);
    EXPECT_EQ(by, 512);
    EXPECT_GE(band->GetOverviewCount(), 1);
  }

  auto read = [&](int band, int x, int y) {
    float v = 0;
    EXPECT_EQ(ds->GetRasterBand(band)->RasterIO(GF_Read, x, y, 1, 1, &v, 1, 1, GDT_Float32, 0, 0, nullptr), CE_None);
    return v;
  };
  for (const auto& [x, y] : std::array<std::pair<int, int>, 4>{{{0, 0}, {599, 299}, {250, 17}, {7, 200}}}) {
    const std::size_t i = static_cast<std::size_t>(y) * 600 + x;
    EXPECT_FLOAT_EQ(read(1, x, y), map.elevation[i]) << x << "," << y;
    EXPECT_FLOAT_EQ(read(3, x, y), map.count[i]) << x << "," << y;
    if (std::isnan(map.uncertainty[i])) {
      EXPECT_TRUE(std::isnan(read(2, x, y)));
    } else {
      EXPECT_FLOAT_EQ(read(2, x, y), map.uncertainty[i]);
    }
  }
  EXPECT_TRUE(std::isnan(read(1, 110, 55))) << "the hole is NoData";
  EXPECT_TRUE(std::isnan(read(3, 110, 55)));
  GDALClose(GDALDataset::ToHandle(ds));
}

TEST_F(TileFiles, GeoTiffWriteFailureNamesThePath) {
  const fs::path path = dir_ / "no" / "such" / "folder" / "map.tif";
  try {
    write_geotiff(sample_map(), "EPSG:32651", path);
    FAIL() << "wrote into a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

// A GeoTIFF the disk refuses (a full scratch disk on the server) is a WriteError, so that a job is
// given back instead of failed for its map; GDAL says it only in words. Files over 1000 bytes
// stand for a full disk. A folder that does not exist stays an ordinary error.
TEST_F(TileFiles, AGeoTiffTheDiskRefusesIsAWriteError) {
  rlimit unlimited{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &unlimited), 0);
  signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG instead of ending the process
  const rlimit small{1000, unlimited.rlim_max};
  auto refused = [&](const std::function<void()>& write) -> std::string {
    EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
    std::string said = "written";
    try {
      write();
    } catch (const WriteError& e) {
      said = e.out_of_space() ? "out of space" : e.what();
    } catch (const std::exception& e) {
      said = e.what();
    }
    EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &unlimited), 0);
    return said;
  };
  EXPECT_EQ(refused([&] { write_geotiff(sample_map(), "EPSG:32651", dir_ / "map.tif"); }), "out of space");
  // The BAG goes through the same copy_to_file and was seen refused as "out of space" too, but
  // GDAL 3.6's BAG driver leaves the half-made HDF5 file open, and HDF5 crashes closing it at the
  // process's exit (H5F__close_cb): not something a test process can be left with.
  try {
    write_geotiff(sample_map(), "EPSG:32651", dir_ / "no" / "map.tif");
    FAIL() << "wrote into a folder that does not exist";
  } catch (const WriteError& e) {
    FAIL() << "a missing folder taken for a full disk: " << e.what();
  } catch (const std::runtime_error&) {
  }
}

TEST_F(TileFiles, VdbReadsBackWithValuesTransformAndMetadata) {
  const GridRaster map = sample_map();
  const fs::path path = dir_ / "map.vdb";
  write_vdb(map, "EPSG:32651", path);

  openvdb::io::File file(path.string());
  file.open();
  auto elevation = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("elevation"));
  auto uncertainty = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("uncertainty"));
  auto count = openvdb::gridPtrCast<openvdb::Int32Grid>(file.readGrid("count"));
  file.close();
  ASSERT_TRUE(elevation && uncertainty && count);

  const GridGeometry& g = map.geometry;
  EXPECT_EQ(elevation->activeVoxelCount(), static_cast<openvdb::Index64>(map.valid_cells()));
  // Raster cell (x, y) is global cell (left + x, top - y) = voxel (i, j, 0).
  for (const auto& [x, y] : std::array<std::pair<int, int>, 3>{{{0, 0}, {599, 299}, {250, 17}}}) {
    const std::size_t i = static_cast<std::size_t>(y) * g.width + x;
    const openvdb::Coord ijk(static_cast<int>(g.left + x), static_cast<int>(g.top - y), 0);
    EXPECT_FLOAT_EQ(elevation->tree().getValue(ijk), map.elevation[i]);
    EXPECT_EQ(count->tree().getValue(ijk), static_cast<int>(map.count[i]));
  }
  const openvdb::Coord hole(static_cast<int>(g.left + 110), static_cast<int>(g.top - 55), 0);
  EXPECT_FALSE(elevation->tree().isValueOn(hole));
  EXPECT_TRUE(std::isnan(elevation->tree().getValue(hole)));
  EXPECT_EQ(count->tree().getValue(hole), 0);

  // One voxel per cell; a voxel's world position is its cell centre in CRS metres.
  const openvdb::math::Transform& t = elevation->transform();
  EXPECT_TRUE(t.isLinear());
  EXPECT_DOUBLE_EQ(t.voxelSize()[0], 0.5);
  EXPECT_DOUBLE_EQ(t.voxelSize()[1], 0.5);
  const openvdb::Vec3d upper_left = t.indexToWorld(openvdb::Coord(static_cast<int>(g.left), static_cast<int>(g.top), 0));
  EXPECT_DOUBLE_EQ(upper_left.x(), 452050.25);
  EXPECT_DOUBLE_EQ(upper_left.y(), 4630149.75);

  EXPECT_EQ(elevation->metaValue<std::string>("crs"), "EPSG:32651");
  EXPECT_DOUBLE_EQ(elevation->metaValue<double>("resolution_m"), 0.5);
  EXPECT_DOUBLE_EQ(elevation->metaValue<double>("origin_easting_m"), 452050.0);
  EXPECT_DOUBLE_EQ(elevation->metaValue<double>("origin_northing_m"), 4630000.0);
  EXPECT_EQ(count->metaValue<std::string>("crs"), "EPSG:32651");
}

TEST_F(TileFiles, VdbRefusesCellIndicesBeyondItsCoordinates) {
  GridRaster far = GridRaster::no_data({0.001, 3'000'000'000, 10, 1, 1});  // easting 3000 km in 1 mm cells
  far.elevation[0] = -10;
  far.count[0] = 3;
  EXPECT_THROW(write_vdb(far, "EPSG:32651", dir_ / "far.vdb"), std::runtime_error);
}

TEST_F(TileFiles, PyramidWritesATifAndAVdbPerTileNamedLevelColRow) {
  const GridRaster map = sample_map();  // 300 m × 150 m from easting 452050: two level-0 tiles wide
  const TileFileCount written = write_tile_files(map, "EPSG:32651", dir_ / "tiles");
  EXPECT_GE(written.levels, 2);
  std::size_t tifs = 0, vdbs = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "tiles")) {
    tifs += entry.path().extension() == ".tif";
    vdbs += entry.path().extension() == ".vdb";
  }
  EXPECT_EQ(tifs, written.tiles);
  EXPECT_EQ(vdbs, written.tiles);
  // Level 0, tile column floor(452050 / 256) = 1765, row floor(4630000 / 256) = 18085.
  const fs::path tile = dir_ / "tiles" / "0" / "1765_18085.tif";
  ASSERT_TRUE(fs::exists(tile));
  GDALDataset* ds = GDALDataset::Open(tile.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  ASSERT_NE(ds, nullptr);
  std::array<double, 6> t{};
  ds->GetGeoTransform(t.data());
  EXPECT_DOUBLE_EQ(t[0], 1765 * 256.0);
  EXPECT_DOUBLE_EQ(t[3], 18086 * 256.0);
  EXPECT_EQ(ds->GetRasterXSize(), 512);
  EXPECT_STREQ(ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE"), "COG");
  GDALClose(GDALDataset::ToHandle(ds));
}

TEST_F(TileFiles, PyramidWriteFailureNamesTheTileFile) {
  // A folder where a tile's GeoTIFF should go: the tile writers (on several threads) must report it.
  const fs::path blocked = dir_ / "tiles" / "0" / "1765_18085.tif";
  fs::create_directories(blocked);
  try {
    write_tile_files(sample_map(), "EPSG:32651", dir_ / "tiles");
    FAIL() << "wrote a tile over a folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(blocked.string()), std::string::npos) << e.what();
  }
}

// Counts pixels of the image by what they look like.
struct PixelKinds {
  int white = 0, bluish = 0, reddish = 0;
};
PixelKinds pixel_kinds(const std::vector<std::uint8_t>& png) {
  const cv::Mat image = cv::imdecode(png, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty());
  PixelKinds k;
  for (auto it = image.begin<cv::Vec3b>(); it != image.end<cv::Vec3b>(); ++it) {
    const cv::Vec3b p = *it;  // BGR
    if (p == cv::Vec3b(255, 255, 255)) ++k.white;
    else if (p[0] > p[2] + 60) ++k.bluish;
    else if (p[2] > p[0] + 60) ++k.reddish;
  }
  return k;
}

TEST_F(TileFiles, HillshadeRampsFromDeepBlueToShallowRed) {
  GridRaster map = sample_map();  // deep in the west, shallow in the east
  const std::vector<std::uint8_t> png = hillshade_png(map, "test");
  const cv::Mat image = cv::imdecode(png, cv::IMREAD_COLOR);
  ASSERT_GE(image.cols, 600);
  const PixelKinds k = pixel_kinds(png);
  EXPECT_GT(k.bluish, 10000);
  EXPECT_GT(k.reddish, 10000);
}

TEST_F(TileFiles, DifferenceShowsWhereOneMapIsShallower) {
  const GridRaster b = sample_map();
  GridRaster a = b;
  for (std::size_t i = 0; i < a.elevation.size(); ++i) {
    if (i % 600 >= 300) a.elevation[i] += 1.0f;  // the eastern half of `a` is 1 m shallower
  }
  const PixelKinds k = pixel_kinds(difference_png(a, b, "a - b"));
  EXPECT_GT(k.reddish, 40000);
  EXPECT_LT(k.bluish, 2000) << "only the colour bar's blue half";
}

}  // namespace
}  // namespace bathyslam

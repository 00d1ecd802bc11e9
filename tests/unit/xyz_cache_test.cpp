// The HTTP endpoint's caches of maps and tiles (server/http/xyz_cache.h).
#include "server/http/xyz_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <thread>

#include <unistd.h>

#include "core/tiles/geotiff_writer.h"

namespace bathyslam::server::http {
namespace {

// A 40 x 30 cell map in UTM 51N as the source a job's COG makes.
XyzCache::Source small_source() {
  GridRaster map = GridRaster::no_data(GridGeometry{0.5, 1'000'000, 7'000'000, 40, 30});
  for (std::size_t i = 0; i < map.geometry.cells(); ++i) map.elevation[i] = -20, map.uncertainty[i] = 0.01f, map.count[i] = 3;
  const auto path = std::filesystem::temp_directory_path() / ("xyz_cache_test_" + std::to_string(::getpid()) + ".tif");
  write_geotiff(map, "EPSG:32651", path);
  std::ifstream in(path, std::ios::binary);
  auto source = std::make_shared<const XyzTileSource>(std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {}),
                                                      "EPSG:32651");
  std::filesystem::remove(path);
  return source;
}

TEST(XyzCache, RequestsThatMissTogetherWaitForOneLoad) {
  XyzCache cache(1 << 20, 1 << 20);
  std::atomic<int> loads{0};
  const auto slow_load = [&] {
    ++loads;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    return small_source();
  };
  XyzCache::Source a, b;
  std::thread first([&] { a = cache.source(7, slow_load); });
  std::thread second([&] { b = cache.source(7, slow_load); });
  first.join();
  second.join();
  EXPECT_EQ(loads.load(), 1);
  EXPECT_EQ(a, b);
  EXPECT_EQ(cache.source(7, slow_load), a) << "held";
  EXPECT_EQ(loads.load(), 1);
}

TEST(XyzCache, AFailedLoadFailsItsWaitersAndIsTriedAgain) {
  XyzCache cache(1 << 20, 1 << 20);
  std::atomic<int> loads{0};
  const auto failing = [&]() -> XyzCache::Source {
    ++loads;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    throw std::runtime_error("job 7 has no map");
  };
  std::atomic<int> failures{0};
  auto ask = [&] {
    try {
      cache.source(7, failing);
    } catch (const std::runtime_error&) {
      ++failures;
    }
  };
  std::thread first(ask), second(ask);
  first.join();
  second.join();
  EXPECT_EQ(failures.load(), 2);
  EXPECT_LE(loads.load(), 2);
  EXPECT_NE(cache.source(7, small_source), nullptr) << "a later request loads again";
}

TEST(XyzCache, AHeldTileNeedsNoSource) {
  XyzCache cache(1 << 20, 1 << 20);
  int sources = 0;
  const auto source = [&] {
    ++sources;
    return small_source();
  };
  const auto png = cache.tile(7, 0, 0, 0, true, source);
  ASSERT_NE(png, nullptr);
  EXPECT_EQ(cache.tile(7, 0, 0, 0, true, source), png);
  EXPECT_EQ(sources, 1);
  EXPECT_EQ(cache.tile(7, 3, 0, 0, true, source), nullptr) << "a tile off the map: none, and that is held too";
  EXPECT_EQ(cache.tile(7, 3, 0, 0, true, source), nullptr);
  EXPECT_EQ(sources, 2);
}

}  // namespace
}  // namespace bathyslam::server::http

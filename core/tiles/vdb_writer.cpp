#include "core/tiles/vdb_writer.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>

#include <openvdb/openvdb.h>

namespace bathyslam {
namespace {

openvdb::math::Transform::Ptr cell_transform(double resolution_m) {
  openvdb::math::Transform::Ptr t = openvdb::math::Transform::createLinearTransform(resolution_m);
  t->postTranslate(openvdb::Vec3d(resolution_m / 2, resolution_m / 2, 0));  // voxel centre = cell centre
  return t;
}

void describe(openvdb::GridBase& grid, const char* name, const GridGeometry& g, std::string_view crs,
              const openvdb::math::Transform::Ptr& transform) {
  grid.setName(name);
  grid.setTransform(transform);
  grid.insertMeta("crs", openvdb::StringMetadata(std::string(crs)));
  grid.insertMeta("resolution_m", openvdb::DoubleMetadata(g.resolution_m));
  grid.insertMeta("origin_easting_m", openvdb::DoubleMetadata(g.west_m()));
  grid.insertMeta("origin_northing_m", openvdb::DoubleMetadata(g.south_m()));
  grid.insertMeta("origin_col", openvdb::Int64Metadata(g.left));
  grid.insertMeta("origin_row", openvdb::Int64Metadata(g.bottom()));
}

}  // namespace

void write_vdb(const GridRaster& raster, std::string_view crs, const std::filesystem::path& path) {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });

  const GridGeometry& g = raster.geometry;
  // OpenVDB coordinates are 32-bit; the lattice's indices stay far inside that for any projected
  // CRS at centimetre cells, but a bad resolution must not wrap silently.
  constexpr std::int64_t kMax = std::numeric_limits<openvdb::Int32>::max(), kMin = std::numeric_limits<openvdb::Int32>::min();
  if (g.left < kMin || g.right() > kMax || g.bottom() < kMin || g.top > kMax) {
    throw std::runtime_error(path.string() + ": cannot write OpenVDB file: cell indices exceed 32 bits");
  }
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  openvdb::FloatGrid::Ptr elevation = openvdb::FloatGrid::create(kNaN);
  openvdb::FloatGrid::Ptr uncertainty = openvdb::FloatGrid::create(kNaN);
  openvdb::Int32Grid::Ptr count = openvdb::Int32Grid::create(0);
  {
    openvdb::FloatGrid::Accessor e = elevation->getAccessor(), u = uncertainty->getAccessor();
    openvdb::Int32Grid::Accessor c = count->getAccessor();
    for (std::int64_t row = g.bottom(); row <= g.top; ++row) {
      for (std::int64_t col = g.left; col <= g.right(); ++col) {
        const std::size_t i = g.index(col, row);
        if (!raster.valid(i)) continue;
        const openvdb::Coord ijk(static_cast<openvdb::Int32>(col), static_cast<openvdb::Int32>(row), 0);
        e.setValue(ijk, raster.elevation[i]);
        if (!std::isnan(raster.uncertainty[i])) u.setValue(ijk, raster.uncertainty[i]);
        c.setValue(ijk, static_cast<openvdb::Int32>(raster.count[i]));
      }
    }
  }
  const openvdb::math::Transform::Ptr transform = cell_transform(g.resolution_m);
  describe(*elevation, "elevation", g, crs, transform);
  describe(*uncertainty, "uncertainty", g, crs, transform);
  describe(*count, "count", g, crs, transform);

  try {
    openvdb::io::File file(path.string());
    file.write({elevation, uncertainty, count});
    file.close();
  } catch (const openvdb::Exception& e) {
    throw std::runtime_error(path.string() + ": cannot write OpenVDB file: " + e.what());
  }
}

}  // namespace bathyslam

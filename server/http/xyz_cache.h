#pragma once
// http (XYZ cache): the tile sources of recently viewed jobs (each its COG in memory) and the
// tiles drawn from them, both bounded in bytes and evicted least recently used first. A map's
// tiles never change once its job has stored them, so nothing else invalidates an entry.
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "core/tiles/xyz_tiles.h"

namespace bathyslam::server::http {

class XyzCache {
 public:
  XyzCache(std::size_t max_source_bytes, std::size_t max_tile_bytes)
      : max_source_bytes_(max_source_bytes), max_tile_bytes_(max_tile_bytes) {}

  // The job's tile source, made by `load` (outside the lock) when it is not held.
  std::shared_ptr<const XyzTileSource> source(std::int64_t job_id,
                                              const std::function<std::shared_ptr<const XyzTileSource>()>& load);
  // The tile's PNG (nullptr: the tile does not meet the map), drawn when it is not held.
  std::shared_ptr<const std::string> tile(std::int64_t job_id, int z, int x, int y, bool shade,
                                          const XyzTileSource& source);

 private:
  template <typename Key, typename Value>
  struct Lru {
    std::list<Key> order;  // most recent first
    std::map<Key, std::pair<Value, typename std::list<Key>::iterator>> entries;
    std::size_t bytes = 0;
  };
  using TileKey = std::tuple<std::int64_t, int, int, int, bool>;
  std::size_t max_source_bytes_, max_tile_bytes_;
  std::mutex mutex_;
  Lru<std::int64_t, std::shared_ptr<const XyzTileSource>> sources_;
  Lru<TileKey, std::shared_ptr<const std::string>> tiles_;
};

}  // namespace bathyslam::server::http

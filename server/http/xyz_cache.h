#pragma once
// http (XYZ cache): the tile sources of recently viewed jobs (each its COG in memory) and the
// tiles drawn from them, both bounded in bytes and evicted least recently used first. A map's
// tiles never change once its job has stored them, so nothing else invalidates an entry.
#include <cstdint>
#include <functional>
#include <future>
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

  using Source = std::shared_ptr<const XyzTileSource>;
  // The job's tile source, made by `load` (outside the lock) when it is not held; requests that
  // miss together wait for one load (a viewer's first screen asks for dozens of tiles at once,
  // and each load holds the COG twice).
  Source source(std::int64_t job_id, const std::function<Source()>& load);
  // The tile's PNG (nullptr: the tile does not meet the map), drawn from `source()` when it is
  // not held: a held tile needs no source.
  std::shared_ptr<const std::string> tile(std::int64_t job_id, int z, int x, int y, bool shade,
                                          const std::function<Source()>& source);

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
  Lru<std::int64_t, Source> sources_;
  std::map<std::int64_t, std::shared_future<Source>> loading_;
  Lru<TileKey, std::shared_ptr<const std::string>> tiles_;
};

}  // namespace bathyslam::server::http

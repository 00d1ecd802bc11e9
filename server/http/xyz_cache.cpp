#include "server/http/xyz_cache.h"

namespace bathyslam::server::http {
namespace {

std::size_t size_of(const std::shared_ptr<const XyzTileSource>& source) { return source->bytes(); }
std::size_t size_of(const std::shared_ptr<const std::string>& png) { return png ? png->size() + 64 : 64; }

// The entry of `key`, moved to the front; nullptr-like empty optional when absent.
template <typename Lru, typename Key>
auto find(Lru& lru, const Key& key) -> std::optional<decltype(lru.entries.begin()->second.first)> {
  const auto it = lru.entries.find(key);
  if (it == lru.entries.end()) return std::nullopt;
  lru.order.splice(lru.order.begin(), lru.order, it->second.second);
  return it->second.first;
}

// Inserts (or replaces) `key`, then drops the least recently used entries past `max_bytes`
// (never the one just inserted).
template <typename Lru, typename Key, typename Value>
void insert(Lru& lru, const Key& key, const Value& value, std::size_t max_bytes) {
  if (const auto it = lru.entries.find(key); it != lru.entries.end()) {
    lru.bytes -= size_of(it->second.first);
    lru.order.erase(it->second.second);
    lru.entries.erase(it);
  }
  lru.order.push_front(key);
  lru.entries.emplace(key, std::make_pair(value, lru.order.begin()));
  lru.bytes += size_of(value);
  while (lru.bytes > max_bytes && lru.order.size() > 1) {
    const auto last = lru.entries.find(lru.order.back());
    lru.bytes -= size_of(last->second.first);
    lru.entries.erase(last);
    lru.order.pop_back();
  }
}

}  // namespace

XyzCache::Source XyzCache::source(std::int64_t job_id, const std::function<Source()>& load) {
  std::unique_lock lock(mutex_);
  if (auto held = find(sources_, job_id)) return *held;
  if (const auto it = loading_.find(job_id); it != loading_.end()) {
    const std::shared_future<Source> pending = it->second;
    lock.unlock();
    return pending.get();  // the loader's refusal, if it failed, is this request's too
  }
  std::promise<Source> promise;
  loading_.emplace(job_id, promise.get_future().share());
  lock.unlock();
  try {
    Source loaded = load();  // seconds for a large map: not under the lock
    lock.lock();
    loading_.erase(job_id);
    insert(sources_, job_id, loaded, max_source_bytes_);
    lock.unlock();
    promise.set_value(loaded);
    return loaded;
  } catch (...) {
    if (!lock.owns_lock()) lock.lock();
    loading_.erase(job_id);
    lock.unlock();
    promise.set_exception(std::current_exception());
    throw;
  }
}

std::shared_ptr<const std::string> XyzCache::tile(std::int64_t job_id, int z, int x, int y, bool shade,
                                                  const std::function<Source()>& source) {
  const TileKey key{job_id, z, x, y, shade};
  {
    const std::lock_guard lock(mutex_);
    if (auto held = find(tiles_, key)) return *held;
  }
  std::shared_ptr<const std::string> png;
  if (auto drawn = source()->tile_png(z, x, y, shade)) png = std::make_shared<const std::string>(drawn->begin(), drawn->end());
  const std::lock_guard lock(mutex_);
  insert(tiles_, key, png, max_tile_bytes_);
  return png;
}

}  // namespace bathyslam::server::http

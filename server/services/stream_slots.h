#pragma once
// A bound on the long-lived streams (WatchJob) one tenant holds open on this server: each open
// stream holds a server thread, and one tenant's thousands of them slowed every other tenant's
// calls to seconds (issue 37). Counted in memory, per server process.
#include <cstdint>
#include <mutex>
#include <optional>
#include <unordered_map>

namespace bathyslam::server {

class StreamSlots {
 public:
  explicit StreamSlots(int per_tenant);  // throws std::invalid_argument below 1
  StreamSlots(const StreamSlots&) = delete;
  StreamSlots& operator=(const StreamSlots&) = delete;

  // One stream's slot, given back when the Slot goes.
  class Slot {
   public:
    Slot(StreamSlots& slots, std::int64_t tenant) : slots_(&slots), tenant_(tenant) {}
    Slot(Slot&& other) noexcept : slots_(other.slots_), tenant_(other.tenant_) { other.slots_ = nullptr; }
    Slot(const Slot&) = delete;
    Slot& operator=(const Slot&) = delete;
    Slot& operator=(Slot&&) = delete;
    ~Slot() {
      if (slots_) slots_->give_back(tenant_);
    }

   private:
    StreamSlots* slots_;
    std::int64_t tenant_;
  };

  // A slot for a stream of `tenant`; nullopt when it holds per_tenant() open already.
  std::optional<Slot> take(std::int64_t tenant);
  int per_tenant() const { return per_tenant_; }

 private:
  void give_back(std::int64_t tenant);

  const int per_tenant_;
  std::mutex mutex_;
  std::unordered_map<std::int64_t, int> open_;
};

}  // namespace bathyslam::server

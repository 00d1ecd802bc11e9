#include "server/services/stream_slots.h"

#include <stdexcept>

namespace bathyslam::server {

StreamSlots::StreamSlots(int per_tenant) : per_tenant_(per_tenant) {
  if (per_tenant_ < 1) throw std::invalid_argument("streams per tenant: at least 1");
}

std::optional<StreamSlots::Slot> StreamSlots::take(std::int64_t tenant) {
  std::lock_guard lock(mutex_);
  int& open = open_[tenant];
  if (open >= per_tenant_) return std::nullopt;
  ++open;
  return std::optional<Slot>(std::in_place, *this, tenant);
}

void StreamSlots::give_back(std::int64_t tenant) {
  std::lock_guard lock(mutex_);
  // A tenant with no stream left takes no memory: the map holds only tenants streaming now.
  if (const auto found = open_.find(tenant); found != open_.end() && --found->second == 0) open_.erase(found);
}

}  // namespace bathyslam::server

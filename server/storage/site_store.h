#pragma once
// Sites: a tenant's surveys of one area, in the order they were added (the first is the datum
// of the site's jobs). The service checks ownership and CRS; the store keeps the order and the
// count consistent under concurrent calls.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/storage/database.h"

namespace bathyslam::storage {

struct SiteRecord {
  std::int64_t id = 0;
  std::int64_t tenant_id = 0;
  std::string name;
  double created_at = 0;                 // seconds since the epoch
  std::vector<std::int64_t> survey_ids;  // in the site's order
};

// A site change the site's state refuses, decided under the site's lock (a concurrent call may
// have added the survey, or filled the site, after the service looked).
class SiteChangeRefused : public std::runtime_error {
 public:
  enum class Kind { kNameTaken, kMember, kNotMember, kFull, kCrs, kGone };
  SiteChangeRefused(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

class SiteStore {
 public:
  explicit SiteStore(ConnectionPool& pool) : pool_(pool) {}

  // Throws SiteChangeRefused (kNameTaken) when the tenant has a site of that name.
  std::int64_t create_site(std::int64_t tenant_id, const std::string& name);
  std::optional<SiteRecord> site(std::int64_t site_id);
  // A tenant's sites by id, after `after_id`, at most `limit`; only `name` when given.
  std::vector<SiteRecord> list_sites(std::int64_t tenant_id, std::int64_t after_id, int limit,
                                     const std::optional<std::string>& name = std::nullopt);
  // Appends the surveys in order, all or none; refuses one already in the site (kMember), a
  // site that would then hold more than `max_surveys` (kFull), surveys of two CRSs (kCrs), and a
  // site or survey deleted meanwhile (kGone).
  void add_surveys(std::int64_t site_id, const std::vector<std::int64_t>& survey_ids, int max_surveys);
  // Takes the surveys out, all or none; kNotMember names one that is not in the site, kGone a
  // site deleted meanwhile.
  void remove_surveys(std::int64_t site_id, const std::vector<std::int64_t>& survey_ids);
  bool delete_site(std::int64_t site_id);

 private:
  ConnectionPool& pool_;
};

}  // namespace bathyslam::storage

#include "server/storage/site_store.h"

#include <algorithm>

namespace bathyslam::storage {
namespace {

constexpr std::string_view kSiteColumns =
    "SELECT t.id, t.tenant_id, t.name, extract(epoch FROM t.created_at)::float8 AS created_at,"
    " coalesce((SELECT string_agg(survey_id::text, ',' ORDER BY position) FROM site_surveys WHERE site_id = t.id), '')"
    " AS survey_ids FROM sites t";

std::vector<SiteRecord> site_records(const Result& rows) {
  std::vector<SiteRecord> sites;
  for (int row = 0; row < rows.rows(); ++row) {
    SiteRecord site;
    site.id = rows.int64(row, "id");
    site.tenant_id = rows.int64(row, "tenant_id");
    site.name = rows.text(row, "name");
    site.created_at = rows.float8(row, "created_at");
    site.survey_ids = parse_id_list(rows.text(row, "survey_ids"));
    sites.push_back(std::move(site));
  }
  return sites;
}

// The site's surveys, read under a lock on the site's row that every change takes first (NO KEY:
// a job inserted for the site meanwhile need not wait).
std::vector<std::int64_t> lock_members(Connection& connection, std::int64_t site_id) {
  if (connection.exec("SELECT 1 FROM sites WHERE id = $1 FOR NO KEY UPDATE", {site_id}).rows() == 0)
    throw SiteChangeRefused(SiteChangeRefused::Kind::kGone, "site " + std::to_string(site_id) + " was deleted meanwhile");
  Result rows = connection.exec("SELECT survey_id FROM site_surveys WHERE site_id = $1 ORDER BY position", {site_id});
  std::vector<std::int64_t> ids;
  for (int row = 0; row < rows.rows(); ++row) ids.push_back(rows.int64(row, "survey_id"));
  return ids;
}

bool contains(const std::vector<std::int64_t>& ids, std::int64_t id) { return std::find(ids.begin(), ids.end(), id) != ids.end(); }

}  // namespace

std::int64_t SiteStore::create_site(std::int64_t tenant_id, const std::string& name) {
  auto connection = pool_.acquire();
  try {
    return connection->exec("INSERT INTO sites (tenant_id, name) VALUES ($1, $2) RETURNING id", {tenant_id, name})
        .int64(0, "id");
  } catch (const DatabaseError& error) {
    if (error.sqlstate() == "23505")
      throw SiteChangeRefused(SiteChangeRefused::Kind::kNameTaken, "name: a site of this name exists already");
    throw;
  }
}

std::optional<SiteRecord> SiteStore::site(std::int64_t site_id) {
  auto connection = pool_.acquire();
  auto found = site_records(connection->exec(std::string(kSiteColumns) + " WHERE t.id = $1", {site_id}));
  if (found.empty()) return std::nullopt;
  return found.front();
}

std::vector<SiteRecord> SiteStore::list_sites(std::int64_t tenant_id, std::int64_t after_id, int limit,
                                              const std::optional<std::string>& name) {
  auto connection = pool_.acquire();
  return site_records(connection->exec(std::string(kSiteColumns) +
                                           " WHERE t.tenant_id = $1 AND t.id > $2 AND ($4::text IS NULL OR t.name = $4)"
                                           " ORDER BY t.id LIMIT $3",
                                       {tenant_id, after_id, limit, name}));
}

void SiteStore::add_surveys(std::int64_t site_id, const std::vector<std::int64_t>& survey_ids, int max_surveys) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  std::vector<std::int64_t> members = lock_members(*connection, site_id);
  for (std::int64_t id : survey_ids) {
    if (contains(members, id))
      throw SiteChangeRefused(SiteChangeRefused::Kind::kMember, "survey " + std::to_string(id) + " is in site " +
                                                                    std::to_string(site_id) + " already");
    members.push_back(id);
  }
  if (static_cast<int>(members.size()) > max_surveys)
    throw SiteChangeRefused(SiteChangeRefused::Kind::kFull,
                            "site " + std::to_string(site_id) + " would hold " + std::to_string(members.size()) +
                                " surveys; a site holds at most " + std::to_string(max_surveys) + " (what one job joins)");
  // The CRSs the site would hold, decided under the lock (the service checked before it, but a
  // concurrent add may have come first). A survey that declares none yet is checked at submit.
  std::string ids;
  for (std::int64_t id : members) ids += (ids.empty() ? "" : ",") + std::to_string(id);
  const Result crs = connection->exec(
      "SELECT DISTINCT crs FROM surveys WHERE id = ANY($1::bigint[]) AND crs <> '' ORDER BY crs", {"{" + ids + "}"});
  if (crs.rows() > 1)
    throw SiteChangeRefused(SiteChangeRefused::Kind::kCrs, "the site would hold surveys in " + std::string(crs.text(0, "crs")) +
                                                               " and " + std::string(crs.text(1, "crs")) +
                                                               ": surveys of one site share a CRS");
  const std::int64_t next =
      connection->exec("SELECT coalesce(max(position) + 1, 0) AS next FROM site_surveys WHERE site_id = $1", {site_id})
          .int64(0, "next");
  try {
    for (std::size_t k = 0; k < survey_ids.size(); ++k)
      connection->exec("INSERT INTO site_surveys (site_id, position, survey_id) VALUES ($1, $2, $3)",
                       {site_id, next + static_cast<std::int64_t>(k), survey_ids[k]});
  } catch (const DatabaseError& error) {
    if (error.sqlstate() == "23503")  // a foreign key: the survey was deleted since the service looked
      throw SiteChangeRefused(SiteChangeRefused::Kind::kGone, "a survey was deleted meanwhile");
    throw;
  }
  transaction.commit();
}

void SiteStore::remove_surveys(std::int64_t site_id, const std::vector<std::int64_t>& survey_ids) {
  auto connection = pool_.acquire();
  Transaction transaction(*connection);
  const std::vector<std::int64_t> members = lock_members(*connection, site_id);
  for (std::int64_t id : survey_ids) {
    if (!contains(members, id))
      throw SiteChangeRefused(SiteChangeRefused::Kind::kNotMember,
                              "survey " + std::to_string(id) + " is not in site " + std::to_string(site_id));
    connection->exec("DELETE FROM site_surveys WHERE site_id = $1 AND survey_id = $2", {site_id, id});
  }
  transaction.commit();
}

bool SiteStore::delete_site(std::int64_t site_id) {
  auto connection = pool_.acquire();
  return connection->exec("DELETE FROM sites WHERE id = $1", {site_id}).affected() == 1;
}

}  // namespace bathyslam::storage

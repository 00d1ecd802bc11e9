#include "server/services/site_service.h"

#include <algorithm>

#include "core/io/problem.h"
#include "server/log.h"

namespace bathyslam::server {
namespace {

namespace storage = bathyslam::storage;

void describe(const storage::SiteRecord& site, v1::Site* reply) {
  reply->set_id(site.id);
  reply->set_name(site.name);
  for (std::int64_t id : site.survey_ids) reply->add_survey_ids(id);
  reply->set_created_at(site.created_at);
}

Refusal refusal(const storage::SiteChangeRefused& refused, const std::string& field) {
  using Kind = storage::SiteChangeRefused::Kind;
  switch (refused.kind()) {
    case Kind::kNameTaken: return Refusal(grpc::StatusCode::ALREADY_EXISTS, refused.what());
    case Kind::kFull: return Refusal(grpc::StatusCode::FAILED_PRECONDITION, field + ": " + refused.what());
    case Kind::kGone: return Refusal(grpc::StatusCode::NOT_FOUND, field + ": " + refused.what());
    case Kind::kCrs:
    case Kind::kMember:
    case Kind::kNotMember: break;
  }
  return invalid(field, refused.what());
}

// The request's survey ids, each the caller's (NOT_FOUND naming survey_ids[k] otherwise, as for
// any id), named once, and in the site's CRS when `crs` is given; `site`: the site they join
// (none may be in it yet) or leave (each must be).
enum class Change { kAdd, kRemove };
std::vector<std::int64_t> named_surveys(ServiceContext& context, std::int64_t tenant, const storage::SiteRecord& site,
                                        const google::protobuf::RepeatedField<std::int64_t>& ids, Change change,
                                        std::string crs = "") {
  if (ids.empty()) throw invalid("survey_ids", "name at least one survey");
  if (ids.size() > kMaxSiteSurveys)
    throw invalid("survey_ids", std::to_string(ids.size()) + " surveys; a site holds at most " + std::to_string(kMaxSiteSurveys));
  std::vector<std::int64_t> surveys;
  for (int k = 0; k < ids.size(); ++k) {
    const std::string field = "survey_ids[" + std::to_string(k) + "]";
    const std::string site_name = "site " + std::to_string(site.id);
    const bool member = std::find(site.survey_ids.begin(), site.survey_ids.end(), ids[k]) != site.survey_ids.end();
    if (std::find(surveys.begin(), surveys.end(), ids[k]) != surveys.end())
      throw invalid(field, "survey " + std::to_string(ids[k]) + " is named twice");
    if (change == Change::kRemove) {
      // Only the site's own surveys: an id that is not one says nothing about whose it is.
      if (!member) throw invalid(field, "survey " + std::to_string(ids[k]) + " is not in " + site_name);
      surveys.push_back(ids[k]);
      continue;
    }
    const storage::SurveyRecord survey = owned_survey(context, tenant, ids[k], field);
    if (member) throw invalid(field, "survey " + std::to_string(survey.id) + " is in " + site_name + " already");
    // A survey whose CRS is not declared yet takes survey.json's at finalize; SubmitJob checks again.
    if (!survey.crs.empty() && !crs.empty() && survey.crs != crs)
      throw invalid(field, "survey " + std::to_string(survey.id) + " is in " + survey.crs + ", the site in " + crs +
                               ": surveys of one site share a CRS");
    if (crs.empty()) crs = survey.crs;
    surveys.push_back(survey.id);
  }
  return surveys;
}

// The site as it is now; NOT_FOUND if a concurrent call deleted it.
storage::SiteRecord site_now(ServiceContext& context, std::int64_t site_id) {
  auto site = context.sites.site(site_id);
  if (!site) throw Refusal(grpc::StatusCode::NOT_FOUND, "site_id: no site " + std::to_string(site_id));
  return *site;
}

// The CRS of the site's surveys: the first one's that declares one ("" when none does yet).
std::string site_crs(ServiceContext& context, const storage::SiteRecord& site) {
  for (std::int64_t id : site.survey_ids)
    if (auto survey = context.surveys.survey(id); survey && !survey->crs.empty()) return survey->crs;
  return "";
}

}  // namespace

grpc::Status SiteService::CreateSite(grpc::ServerContext* call, const v1::CreateSiteRequest* request, v1::Site* reply) {
  return handle("CreateSite", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    if (request->name().empty()) throw invalid("name", "a site needs a name");
    check_name("name", request->name());
    const auto same_name = context_.sites.list_sites(tenant, 0, 1, request->name());
    if (!same_name.empty())
      throw Refusal(grpc::StatusCode::ALREADY_EXISTS, "name: site " + std::to_string(same_name.front().id) + " is named " +
                                                          quoted_input(request->name()) + " already");
    std::int64_t id = 0;
    try {  // another call may take the name between the look above and the insert
      id = context_.sites.create_site(tenant, request->name());
    } catch (const storage::SiteChangeRefused& refused) {
      throw refusal(refused, "name");
    }
    log("site %lld created: %s", static_cast<long long>(id), quoted_input(request->name()).c_str());
    describe(site_now(context_, id), reply);
  });
}

grpc::Status SiteService::AddSurveys(grpc::ServerContext* call, const v1::AddSurveysRequest* request, v1::Site* reply) {
  return handle("AddSurveys", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const storage::SiteRecord site = owned_site(context_, tenant, request->site_id());
    const std::vector<std::int64_t> surveys =
        named_surveys(context_, tenant, site, request->survey_ids(), Change::kAdd, site_crs(context_, site));
    try {
      context_.sites.add_surveys(site.id, surveys, kMaxSiteSurveys);
    } catch (const storage::SiteChangeRefused& refused) {
      throw refusal(refused, refused.kind() == storage::SiteChangeRefused::Kind::kGone ? "site_id" : "survey_ids");
    }
    describe(site_now(context_, site.id), reply);
  });
}

grpc::Status SiteService::RemoveSurveys(grpc::ServerContext* call, const v1::RemoveSurveysRequest* request,
                                        v1::Site* reply) {
  return handle("RemoveSurveys", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const storage::SiteRecord site = owned_site(context_, tenant, request->site_id());
    const std::vector<std::int64_t> surveys = named_surveys(context_, tenant, site, request->survey_ids(), Change::kRemove);
    try {
      context_.sites.remove_surveys(site.id, surveys);
    } catch (const storage::SiteChangeRefused& refused) {
      throw refusal(refused, refused.kind() == storage::SiteChangeRefused::Kind::kGone ? "site_id" : "survey_ids");
    }
    describe(site_now(context_, site.id), reply);
  });
}

grpc::Status SiteService::GetSite(grpc::ServerContext* call, const v1::GetSiteRequest* request, v1::Site* reply) {
  return handle("GetSite", call, [&] { describe(owned_site(context_, caller_tenant(context_, *call), request->site_id()), reply); });
}

grpc::Status SiteService::ListSites(grpc::ServerContext* call, const v1::ListSitesRequest* request,
                                    v1::ListSitesResponse* reply) {
  return handle("ListSites", call, [&] {
    const std::int64_t tenant = caller_tenant(context_, *call);
    const int size = page_size(request->page_size());
    const std::optional<std::string> name = name_filter("name", request->name());
    auto sites = context_.sites.list_sites(tenant, page_token(request->page_token()), size + 1, name);
    const bool more = trim_to_page(sites, size);
    for (const storage::SiteRecord& site : sites) describe(site, reply->add_sites());
    if (more) reply->set_next_page_token(std::to_string(sites.back().id));
  });
}

grpc::Status SiteService::DeleteSite(grpc::ServerContext* call, const v1::DeleteSiteRequest* request,
                                     v1::DeleteSiteResponse*) {
  return handle("DeleteSite", call, [&] {
    const storage::SiteRecord site = owned_site(context_, caller_tenant(context_, *call), request->site_id());
    context_.sites.delete_site(site.id);
    log("site %lld deleted", static_cast<long long>(site.id));
  });
}

}  // namespace bathyslam::server

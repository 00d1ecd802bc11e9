// bathyslam site create / add / remove / list / show / delete: a tenant's surveys of one area,
// grouped so that `submit --site` joins them in one graph.
#include <cstdio>
#include <ctime>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "bathyslam/v1/site.grpc.pb.h"
#include "client/commands.h"
#include "client/remote.h"
#include "core/types/format.h"

namespace bathyslam::cli {
namespace {

struct SiteOptions {
  Remote remote;
  std::string name;
  std::int64_t site = 0;
  std::vector<std::int64_t> surveys;
};

std::string ids_text(const google::protobuf::RepeatedField<std::int64_t>& ids) {
  std::string text;
  for (std::int64_t id : ids) text += (text.empty() ? "" : ",") + std::to_string(id);
  return text.empty() ? "-" : text;
}

void print_site(const v1::Site& site) {
  std::printf("site %lld %s: surveys %s (the first is the datum)\n", static_cast<long long>(site.id()), site.name().c_str(),
              ids_text(site.survey_ids()).c_str());
}

std::unique_ptr<v1::SiteService::Stub> stub(const SiteOptions& o) { return v1::SiteService::NewStub(o.remote.channel()); }

void run_create(const SiteOptions& o) {
  v1::CreateSiteRequest request;
  request.set_name(o.name);
  v1::Site site;
  check("CreateSite", stub(o)->CreateSite(o.remote.context(30).get(), request, &site));
  print_site(site);
}

// AddSurveys or RemoveSurveys: the options' site and surveys, the site as it is then.
template <typename Request, typename Call>
void change_surveys(const SiteOptions& o, const char* name, Call call) {
  Request request;
  request.set_site_id(o.site);
  for (std::int64_t id : o.surveys) request.add_survey_ids(id);
  v1::Site site;
  auto sites = stub(o);
  check(name, ((*sites).*call)(o.remote.context(30).get(), request, &site));
  print_site(site);
}

void run_add(const SiteOptions& o) { change_surveys<v1::AddSurveysRequest>(o, "AddSurveys", &v1::SiteService::Stub::AddSurveys); }

void run_remove(const SiteOptions& o) {
  change_surveys<v1::RemoveSurveysRequest>(o, "RemoveSurveys", &v1::SiteService::Stub::RemoveSurveys);
}

void run_show(const SiteOptions& o) {
  v1::GetSiteRequest request;
  request.set_site_id(o.site);
  v1::Site site;
  check("GetSite", stub(o)->GetSite(o.remote.context(30).get(), request, &site));
  print_site(site);
}

void run_list(const SiteOptions& o) {
  auto sites = stub(o);
  v1::ListSitesRequest request;
  std::printf("%6s  %-19s  %-30s  %s\n", "site", "created (UTC)", "name", "surveys (the first is the datum)");
  do {
    v1::ListSitesResponse page;
    check("ListSites", sites->ListSites(o.remote.context(30).get(), request, &page));
    for (const v1::Site& site : page.sites())
      std::printf("%6lld  %-19s  %-30s  %s\n", static_cast<long long>(site.id()),
                  format_utc(site.created_at(), "%Y-%m-%d %H:%M:%S").c_str(), site.name().c_str(),
                  ids_text(site.survey_ids()).c_str());
    request.set_page_token(page.next_page_token());
  } while (!request.page_token().empty());
}

void run_delete(const SiteOptions& o) {
  v1::DeleteSiteRequest request;
  request.set_site_id(o.site);
  v1::DeleteSiteResponse reply;
  check("DeleteSite", stub(o)->DeleteSite(o.remote.context(30).get(), request, &reply));
  std::printf("site %lld deleted (its surveys and jobs stay)\n", static_cast<long long>(o.site));
}

// A subcommand of `site` with its options and the remote options, running `run` on them.
CLI::App* site_subcommand(CLI::App* site, const char* name, const char* help, void (*run)(const SiteOptions&),
                          const std::shared_ptr<SiteOptions>& options) {
  CLI::App* cmd = site->add_subcommand(name, help);
  add_remote_options(cmd, options->remote);
  cmd->callback([options, run] { run(*options); });
  return cmd;
}

}  // namespace

void add_site_commands(CLI::App& app) {
  CLI::App* site = app.add_subcommand("site", "Sites: surveys of one area grouped for jobs that join them (submit --site)");
  site->require_subcommand(1);
  auto create = std::make_shared<SiteOptions>();
  site_subcommand(site, "create", "Create an empty site; prints its id", run_create, create)
      ->add_option("name", create->name, "the site's name, unique among yours")
      ->required();
  for (auto [name, help, run] : {std::tuple{"add", "Append surveys to a site, in order (the site's first is the datum)", &run_add},
                                 std::tuple{"remove", "Take surveys out of a site (the surveys stay)", &run_remove}}) {
    auto options = std::make_shared<SiteOptions>();
    CLI::App* cmd = site_subcommand(site, name, help, run, options);
    cmd->add_option("site", options->site, "site id")->required();
    cmd->add_option("surveys", options->surveys, "survey ids")->required();
  }
  for (auto [name, help, run] : {std::tuple{"show", "A site's surveys in order", &run_show},
                                 std::tuple{"delete", "Delete a site (its surveys and jobs stay)", &run_delete}}) {
    auto options = std::make_shared<SiteOptions>();
    site_subcommand(site, name, help, run, options)->add_option("site", options->site, "site id")->required();
  }
  site_subcommand(site, "list", "Your sites", run_list, std::make_shared<SiteOptions>());
}

}  // namespace bathyslam::cli

#pragma once
// bathyslam.v1.SiteService: a tenant's surveys of one area, grouped for jobs that join them.
#include "bathyslam/v1/site.grpc.pb.h"
#include "server/services/service_context.h"

namespace bathyslam::server {

class SiteService final : public v1::SiteService::Service {
 public:
  explicit SiteService(ServiceContext& context) : context_(context) {}

  grpc::Status CreateSite(grpc::ServerContext* call, const v1::CreateSiteRequest* request, v1::Site* reply) override;
  grpc::Status AddSurveys(grpc::ServerContext* call, const v1::AddSurveysRequest* request, v1::Site* reply) override;
  grpc::Status RemoveSurveys(grpc::ServerContext* call, const v1::RemoveSurveysRequest* request, v1::Site* reply) override;
  grpc::Status GetSite(grpc::ServerContext* call, const v1::GetSiteRequest* request, v1::Site* reply) override;
  grpc::Status ListSites(grpc::ServerContext* call, const v1::ListSitesRequest* request,
                         v1::ListSitesResponse* reply) override;
  grpc::Status DeleteSite(grpc::ServerContext* call, const v1::DeleteSiteRequest* request,
                          v1::DeleteSiteResponse* reply) override;

 private:
  ServiceContext& context_;
};

}  // namespace bathyslam::server

#pragma once
// bathyslam.v1.MapService: a job's map tiles, whole map and optimized trajectory, served from
// what the scheduler stored (tables tiles, maps, submaps, optimized_poses).
#include "bathyslam/v1/map.grpc.pb.h"
#include "server/services/service_context.h"

namespace bathyslam::server {

class MapService final : public v1::MapService::Service {
 public:
  explicit MapService(ServiceContext& context) : context_(context) {}

  grpc::Status GetMapInfo(grpc::ServerContext* call, const v1::GetMapInfoRequest* request, v1::MapInfo* reply) override;
  grpc::Status GetTile(grpc::ServerContext* call, const v1::GetTileRequest* request,
                       grpc::ServerWriter<v1::DataChunk>* writer) override;
  grpc::Status GetMap(grpc::ServerContext* call, const v1::GetMapRequest* request,
                      grpc::ServerWriter<v1::DataChunk>* writer) override;
  grpc::Status GetTrajectory(grpc::ServerContext* call, const v1::GetTrajectoryRequest* request,
                             v1::Trajectory* reply) override;

 private:
  ServiceContext& context_;
};

}  // namespace bathyslam::server

"""bathyslam's Python client: upload a survey (resuming a cut upload), run a SLAM job, watch it,
read its report and download its map, over the gRPC API with Debian's python3-grpcio.

    from bathyslam import Client
    with Client("127.0.0.1:50051", token) as client:
        survey = client.upload("demo/small")
        job = client.submit(survey, "mchs")
        client.watch(job, progress=lambda stage, fraction, message: print(stage, fraction))
        print(client.report(job)["consistency_error_m"]["optimized"]["rmse"])
        client.download_map(job, "map.tif")
"""
from bathyslam.client import Client
from bathyslam.errors import (BathyslamError, FailedPrecondition, InvalidArgument, JobFailed, NotFound,
                              ResourceExhausted, Unauthenticated, Unavailable)

__all__ = ["Client", "BathyslamError", "FailedPrecondition", "InvalidArgument", "JobFailed", "NotFound",
           "ResourceExhausted", "Unauthenticated", "Unavailable"]

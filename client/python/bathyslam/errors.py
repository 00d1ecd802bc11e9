"""The service's refusals as exceptions: one class per gRPC status code a caller can act on, each
with the server's message (which names the file, field or limit at fault)."""
import grpc


class BathyslamError(Exception):
    """A call the service refused or could not answer: `code` (grpc.StatusCode), `details`."""

    def __init__(self, call, code, details):
        super().__init__(f"{call}: {code.name}: {details}")
        self.call, self.code, self.details = call, code, details


class InvalidArgument(BathyslamError):
    """The request or the uploaded data is wrong; the message says where."""


class Unauthenticated(BathyslamError):
    """No token, or an unknown, expired or revoked one."""


class NotFound(BathyslamError):
    """No such survey or job for this tenant (another tenant's ids answer the same)."""


class FailedPrecondition(BathyslamError):
    """Not in this state: e.g. the report of a job that has not finished."""


class ResourceExhausted(BathyslamError):
    """A limit of the tenant or the server: the message names it."""


class Unavailable(BathyslamError):
    """The server or its database is away for now: try again (uploads resume)."""


class JobFailed(Exception):
    """A watched job ended failed or cancelled: `job` is its last state (a dict)."""

    def __init__(self, job):
        super().__init__(f"job {job['id']} {job['state']}: {job.get('error') or 'no error message'}")
        self.job = job


_BY_CODE = {grpc.StatusCode.INVALID_ARGUMENT: InvalidArgument, grpc.StatusCode.UNAUTHENTICATED: Unauthenticated,
            grpc.StatusCode.NOT_FOUND: NotFound, grpc.StatusCode.FAILED_PRECONDITION: FailedPrecondition,
            grpc.StatusCode.RESOURCE_EXHAUSTED: ResourceExhausted, grpc.StatusCode.UNAVAILABLE: Unavailable}


def error_of(call, error):
    """The BathyslamError (its subclass by code) of a grpc.RpcError raised by `call`."""
    return _BY_CODE.get(error.code(), BathyslamError)(call, error.code(), error.details())

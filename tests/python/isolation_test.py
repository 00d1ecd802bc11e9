#!/usr/bin/env python3
"""Tenant isolation, RPC by RPC: every method of every bathyslam service, read from the
service descriptors (a new RPC without a case here fails the test), called with no token, a
wrong token, a revoked token, another tenant's token and the owner's token. The first three
are UNAUTHENTICATED; another tenant's token finds nothing of the owner's (NOT_FOUND naming the
id, or a list without the owner's ids), never PERMISSION_DENIED, which would tell that the id
exists; only the owner's token gets the owner's data. After every refused call the database is
unchanged. The same environment as service_api_test.py (set by ctest)."""
import unittest

import grpc
from google.protobuf import descriptor_pb2, symbol_database

from service_api_test import (Server, database_fingerprint, job_pb2, map_pb2, psql, read, ready_survey,
                              restart_asking_for_tokens, site_pb2, survey_pb2, upload_requests)
from reliability_test import final_state

SERVICES = [module.DESCRIPTOR.services_by_name[name]
            for module, name in ((survey_pb2, "SurveyService"), (job_pb2, "JobService"), (map_pb2, "MapService"),
                                 (site_pb2, "SiteService"))]
NOBODY = ("no token", "wrong token", "revoked token")


def method_kind(method):
    """(client streaming, server streaming) of a method descriptor."""
    proto = descriptor_pb2.MethodDescriptorProto()
    method.CopyToProto(proto)
    return proto.client_streaming, proto.server_streaming


def message_class(descriptor):
    return symbol_database.Default().GetSymbol(descriptor.full_name)


class IsolationMatrixTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # The owner's data is made on a development server (its dev tenant is the owner), which
        # then restarts asking every caller for a token.
        cls.server = Server(dev_tenant="owner")
        s = cls.server
        cls.ready = ready_survey(s.surveys, "ready")
        cls.doomed = s.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name="doomed"), timeout=30).id
        cls.uploading = s.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name="uploading"), timeout=30).id
        job = s.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=cls.ready, configuration="odometry"), timeout=30)
        assert final_state(s, job.id).state == job_pb2.SUCCEEDED, s.server_log()
        cls.job = job.id
        cls.tile = next(t for t in s.maps.GetMapInfo(map_pb2.GetMapInfoRequest(job_id=job.id), timeout=30).tiles)
        cls.site = s.sites.CreateSite(site_pb2.CreateSiteRequest(name="site"), timeout=30).id
        s.sites.AddSurveys(site_pb2.AddSurveysRequest(site_id=cls.site, survey_ids=[cls.ready]), timeout=30)
        cls.tokens = restart_asking_for_tokens(s)
        cls.owner_tenant, cls.intruder_tenant = (int(psql(s.url, f"SELECT id FROM tenants WHERE name = '{name}'"))
                                                 for name in ("owner", "intruder"))
        cls.created = 0

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def request(self, method):
        """The method's request (or request stream) aimed at the owner's data. Fields are filled
        by name; a method this table does not know fails the test with its name."""
        self.__class__.created += 1
        cases = {
            "CreateSurvey": dict(name=f"created {self.created}"),
            "UploadFile": None,
            "GetUploadStatus": dict(survey_id=self.uploading, file_name="survey.json"),
            "FinalizeSurvey": dict(survey_id=self.ready),
            "GetSurvey": dict(survey_id=self.ready),
            "ListSurveys": dict(),
            "DeleteSurvey": dict(survey_id=self.doomed),
            "SubmitJob": dict(survey_id=self.ready, configuration="odometry"),
            "GetJob": dict(job_id=self.job),
            "WatchJob": dict(job_id=self.job),
            "CancelJob": dict(job_id=self.job),
            "ListJobs": dict(),
            "GetReport": dict(job_id=self.job),
            "GetMapInfo": dict(job_id=self.job),
            "GetTile": dict(job_id=self.job, level=self.tile.level, col=self.tile.col, row=self.tile.row,
                            format=map_pb2.GEOTIFF),
            "GetMap": dict(job_id=self.job),
            "GetTrajectory": dict(job_id=self.job),
            "CreateSite": dict(name=f"created {self.created}"),
            # The owner adds a survey that the next case takes out again.
            "AddSurveys": dict(site_id=self.site, survey_ids=[self.uploading]),
            "RemoveSurveys": dict(site_id=self.site, survey_ids=[self.uploading]),
            "GetSite": dict(site_id=self.site),
            "ListSites": dict(),
            "DeleteSite": dict(site_id=self.site),
        }
        self.assertIn(method.name, cases, f"{method.full_name} has no case in the isolation matrix")
        if method.name == "UploadFile":
            return upload_requests(self.uploading, "survey.json", read("survey.json"))
        return message_class(method.input_type)(**cases[method.name])

    def call(self, method, who):
        """(status code, details, reply messages) of one call as `who`."""
        channel = self.server.channel
        path = f"/{method.containing_service.full_name}/{method.name}"
        client_streaming, server_streaming = method_kind(method)
        kind = {(False, False): channel.unary_unary, (False, True): channel.unary_stream,
                (True, False): channel.stream_unary}[(client_streaming, server_streaming)]
        stub = kind(path, request_serializer=lambda m: m.SerializeToString(),
                    response_deserializer=message_class(method.output_type).FromString)
        metadata = [] if who == "no token" else [("authorization", "Bearer " + self.tokens[who])]
        try:
            reply = stub(self.request(method), metadata=metadata, timeout=60)
            return grpc.StatusCode.OK, "", list(reply) if server_streaming else [reply]
        except grpc.RpcError as error:
            return error.code(), error.details(), []

    def fingerprint(self):
        """The whole database but another tenant's surveys: what it may create in its own space."""
        return database_fingerprint(self.server.url, {"surveys": f"tenant_id <> {self.intruder_tenant}",
                                                      "sites": f"tenant_id <> {self.intruder_tenant}"})

    def owner_ids(self):
        """The owner's surveys, job and site as (list field, id): ids of different kinds may be equal."""
        surveys = {("surveys", s.id) for s in self.server.surveys.ListSurveys(
            survey_pb2.ListSurveysRequest(), metadata=[("authorization", "Bearer " + self.tokens["owner"])], timeout=30).surveys}
        return surveys | {("jobs", self.job), ("sites", self.site)}

    def listed(self, replies):
        return {(field, item.id) for reply in replies for field in ("surveys", "jobs", "sites")
                for item in getattr(reply, field, [])}

    def test_every_rpc_against_every_caller(self):
        methods = [method for service in SERVICES for method in service.methods]
        self.assertGreaterEqual(len(methods), 23)
        # Nothing a refused caller sends changes the owner's data or anyone else's; what another
        # tenant creates in its own space (CreateSurvey) is left out of the comparison.
        before = self.fingerprint()
        for method in methods:
            for who in NOBODY:
                with self.subTest(method=method.name, caller=who):
                    code, details, _ = self.call(method, who)
                    self.assertEqual(code, grpc.StatusCode.UNAUTHENTICATED, details)
                    self.assertIn("authorization", details)
                    self.assertEqual(self.fingerprint(), before,
                                     "a refused call changed the database")
            with self.subTest(method=method.name, caller="another tenant"):
                code, details, replies = self.call(method, "another tenant")
                self.assertNotEqual(code, grpc.StatusCode.PERMISSION_DENIED, details)
                if method.name in ("ListSurveys", "ListJobs", "ListSites", "CreateSurvey", "CreateSite"):
                    self.assertEqual(code, grpc.StatusCode.OK, details)
                    self.assertFalse(self.listed(replies) & self.owner_ids(), "another tenant lists the owner's data")
                else:
                    self.assertEqual(code, grpc.StatusCode.NOT_FOUND, details)
                    self.assertRegex(details, r"^(survey_id|job_id|site_id): no (survey|job|site) \d+$")
                self.assertEqual(self.fingerprint(), before,
                                 "another tenant's call changed the database")
        # Then the owner, who may change things: DeleteSurvey last, as it removes what it is aimed at.
        for method in sorted(methods, key=lambda method: method.name == "DeleteSurvey"):
            with self.subTest(method=method.name, caller="owner"):
                code, details, replies = self.call(method, "owner")
                # A finished job cannot be cancelled: refused for what it is, not for who asks.
                expected = grpc.StatusCode.FAILED_PRECONDITION if method.name == "CancelJob" else grpc.StatusCode.OK
                self.assertEqual(code, expected, details)
                if method.name in ("ListSurveys", "ListJobs", "ListSites"):
                    self.assertTrue(self.listed(replies) & self.owner_ids(), f"{method.name} misses the owner's data")
        self.assertIsNone(self.server.process.poll(), "the server died:\n" + self.server.server_log())

if __name__ == "__main__":
    unittest.main(verbosity=2)

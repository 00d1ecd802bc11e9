#!/usr/bin/env python3
"""The server under a database outage and hostile input: it must stay up, say what is wrong,
and finish the work it took. The same environment as service_api_test.py (set by ctest), whose
Server and helpers this reuses: a real bathyslam-server on a real PostgreSQL."""
import subprocess
import time
import unittest

import grpc

from service_api_test import (ENV, OwnCluster, Server, health_pb2, job_pb2, map_pb2, read, ready_survey, survey_pb2,
                              upload_requests)

SERVING = health_pb2.HealthCheckResponse.SERVING
NOT_SERVING = health_pb2.HealthCheckResponse.NOT_SERVING


def pg(command, cluster):
    subprocess.run(["bash", ENV["PG_SH"], command, cluster], check=True, capture_output=True)


def poses(server, job_id):
    """A job's optimized poses, as exact numbers."""
    trajectory = server.maps.GetTrajectory(map_pb2.GetTrajectoryRequest(job_id=job_id), timeout=30)
    return [(p.submap, str(p.optimized).replace("\n", " ")) for p in trajectory.poses]


def final_state(server, job_id, seconds=300):
    """The job's state once it has ended, riding out UNAVAILABLE answers while the database is away."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            job = server.jobs.GetJob(job_pb2.GetJobRequest(job_id=job_id), timeout=30)
            if job.state not in (job_pb2.QUEUED, job_pb2.RUNNING):
                return job
        except grpc.RpcError as error:
            if error.code() != grpc.StatusCode.UNAVAILABLE:
                raise
        time.sleep(0.5)
    raise AssertionError(f"job {job_id} did not end within {seconds} s")


class OutageTest(OwnCluster):
    def assert_alive(self):
        self.assertIsNone(self.server.process.poll(), "the server died:\n" + self.server.server_log())

    def outage(self, seconds):
        """The cluster stopped for `seconds`: health follows it, the server stays up."""
        stopped = time.monotonic()
        pg("stop", self.cluster)
        self.assertEqual(self.wait_for(NOT_SERVING), NOT_SERVING, self.server.server_log())
        while time.monotonic() - stopped < seconds:
            self.assert_alive()
            time.sleep(0.5)
        pg("start", self.cluster)
        self.assertEqual(self.wait_for(SERVING), SERVING, self.server.server_log())
        self.assert_alive()


class JobThroughOutageTest(OutageTest):
    def test_a_job_survives_the_database_stopping_mid_job(self):
        survey_id = ready_survey(self.server.surveys, "outage")
        job = self.server.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="mchs"), timeout=30)
        for event in self.server.jobs.WatchJob(job_pb2.WatchJobRequest(job_id=job.id), timeout=120):
            self.assertNotIn(event.state, (job_pb2.SUCCEEDED, job_pb2.FAILED), "the job ended before the outage")
            if event.stage == "register":
                break
        self.outage(15)  # while it registers: heartbeats, state polls and progress events fail
        while (now := self.server.jobs.GetJob(job_pb2.GetJobRequest(job_id=job.id), timeout=30)).stage not in ("map", "store"):
            self.assertEqual(now.state, job_pb2.RUNNING, now.error + self.server.server_log())
            time.sleep(0.1)
        self.outage(8)  # while it fuses the map and stores its results

        disturbed = final_state(self.server, job.id)
        log = self.server.server_log()
        self.assertEqual(disturbed.state, job_pb2.SUCCEEDED, disturbed.error + log)
        # The outages cost retries, not the attempt.
        self.assertEqual(disturbed.attempts, 1, log)
        self.assertIn("storing results: succeeded after", log)
        self.assert_alive()
        # The same job undisturbed: the outage changed nothing in what the job computed.
        again = self.server.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="mchs"), timeout=30)
        self.assertEqual(final_state(self.server, again.id).state, job_pb2.SUCCEEDED, self.server.server_log())
        self.assertEqual(poses(self.server, job.id), poses(self.server, again.id))
        self.assertGreater(len(poses(self.server, job.id)), 5)
        print(f"\njob through two outages: {disturbed.finished_at - disturbed.started_at:.1f} s", flush=True)


class HostileJsonTest(unittest.TestCase):
    """JSON built to crash its reader (nested 100 000 deep: about 200 KB, under the message
    limit) is refused with the field named, and the server stays up and unchanged."""

    @classmethod
    def setUpClass(cls):
        cls.server = Server()
        cls.surveys = cls.server.surveys

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def refused(self, call, request):
        with self.assertRaises(grpc.RpcError) as raised:
            call(request, timeout=60)
        self.assertIsNone(self.server.process.poll(), "the server died:\n" + self.server.server_log())
        self.assertEqual(raised.exception.code(), grpc.StatusCode.INVALID_ARGUMENT, raised.exception.details())
        return raised.exception.details()

    def test_deeply_nested_sonar_and_vehicle_json(self):
        deep = '{"a": ' + "[" * 100000 + "]" * 100000 + "}"
        for field in ("sonar_json", "vehicle_json"):
            details = self.refused(self.surveys.CreateSurvey,
                                   survey_pb2.CreateSurveyRequest(name="deep " + field, **{field: deep}))
            self.assertEqual(details, field + ": nested deeper than 64 levels")
        huge = '{"a": "' + "x" * (1536 << 10) + '"}'
        self.assertEqual(self.refused(self.surveys.CreateSurvey, survey_pb2.CreateSurveyRequest(name="huge", sonar_json=huge)),
                         "sonar_json: larger than 1048576 bytes")
        listed = self.surveys.ListSurveys(survey_pb2.ListSurveysRequest(), timeout=30)
        self.assertEqual([s.name for s in listed.surveys if s.name.startswith(("deep", "huge"))], [])

    def test_deeply_nested_survey_json_in_an_upload(self):
        survey_id = self.surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name="deep bundle"), timeout=30).id
        deep = ('{"name": "deep", "crs": "EPSG:32651", "sonar": {"a": ' + "[" * 100000 + "]" * 100000 + "}}").encode()
        self.assertTrue(self.surveys.UploadFile(upload_requests(survey_id, "survey.json", deep), timeout=60).complete)
        for name in ("nav.csv", "pings.csv"):
            self.surveys.UploadFile(upload_requests(survey_id, name, read(name)), timeout=120)
        details = self.refused(self.surveys.FinalizeSurvey, survey_pb2.FinalizeSurveyRequest(survey_id=survey_id))
        self.assertIn("survey.json: nested deeper than 64 levels", details)
        survey = self.surveys.GetSurvey(survey_pb2.GetSurveyRequest(survey_id=survey_id), timeout=30)
        self.assertEqual(survey.state, survey_pb2.Survey.UPLOADING)
        # A survey.json over its limit is refused when declared, before a byte is stored.
        big = b'{"name": "big", "crs": "EPSG:32651", "sonar": {"a": "' + b"x" * (2 << 20) + b'"}}'
        details = self.refused(self.surveys.UploadFile, upload_requests(survey_id, "survey.json", big))
        self.assertEqual(details, f"size_bytes: survey.json is at most 1048576 bytes, not {len(big)}")


if __name__ == "__main__":
    unittest.main(verbosity=2)

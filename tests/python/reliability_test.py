#!/usr/bin/env python3
"""The server under a database outage, a restart and a kill: it must stay up, say what is wrong,
and finish the work it took. The same environment as service_api_test.py (set by ctest), whose
Server and helpers this reuses: a real bathyslam-server on a real PostgreSQL."""
import hashlib
import os
import re
import signal
import subprocess
import time
import unittest

import grpc

from service_api_test import (BUNDLE, ENV, OwnCluster, Server, health_pb2, job_pb2, map_pb2, psql, read, ready_survey,
                              token)

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

    def outage(self, seconds, paused=None):
        """The cluster stopped for `seconds`: health follows it, the server stays up. `paused`: a
        process (the server, an uploading CLI) stopped with SIGSTOP while the cluster stops, so that
        the work under test is still where it was when the outage begins, however fast the machine."""
        if paused:
            os.kill(paused, signal.SIGSTOP)
        stopped = time.monotonic()
        try:
            pg("stop", self.cluster)
        finally:
            if paused:
                os.kill(paused, signal.SIGCONT)
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
        self.outage(15, paused=self.server.process.pid)  # while it registers: heartbeats, state polls and progress events fail
        while (now := self.server.jobs.GetJob(job_pb2.GetJobRequest(job_id=job.id), timeout=30)).stage not in ("map", "store"):
            self.assertEqual(now.state, job_pb2.RUNNING, now.error + self.server.server_log())
            time.sleep(0.02)
        self.outage(8, paused=self.server.process.pid)  # while it fuses the map and stores its results

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


class UploadThroughRestartTest(OutageTest):
    def test_an_upload_survives_the_database_restarting_in_the_middle(self):
        """`bathyslam upload` waits out the restart and resumes where the server's committed
        bytes end; the stored file hashes to the local one (the server checks the declared
        SHA-256 once the last byte is in, and the test compares it with the file's)."""
        cli = subprocess.Popen([ENV["BATHYSLAM"], "upload", BUNDLE, "--name", "restarted", "--server", self.server.address],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.addCleanup(lambda: cli.poll() is None and cli.kill())
        committed = "SELECT coalesce(max(committed_bytes), 0) FROM survey_files WHERE name = 'pings.csv'"
        deadline = time.monotonic() + 120
        while int(psql(self.server.url, committed) or 0) < 8 << 20:
            self.assertIsNone(cli.poll(), "the upload ended before the restart")
            self.assertLess(time.monotonic(), deadline, "pings.csv never started")
            time.sleep(0.05)
        self.outage(3, paused=cli.pid)
        out, err = cli.communicate(timeout=300)
        self.assertEqual(cli.returncode, 0, err + self.server.server_log())
        self.assertRegex(out, r"survey \d+ ready")
        self.assertIn("trying again", err)
        self.assertIn("resuming pings.csv", err)
        stored = psql(self.server.url, "SELECT encode(sha256, 'hex'), committed_bytes, complete FROM survey_files"
                                       " WHERE name = 'pings.csv'")
        self.assertEqual(stored, f"{hashlib.sha256(read('pings.csv')).hexdigest()}|{len(read('pings.csv'))}|t")


class ReflectionTest(unittest.TestCase):
    """Reflection is offered by a development server or one told to, and asks for a token like the API."""

    @staticmethod
    def list_services(server, metadata=()):
        call = server.channel.stream_stream("/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo")
        # ServerReflectionRequest{list_services: ""}, field 7, serialised by hand.
        return list(call(iter([b"\x3a\x00"]), metadata=metadata, timeout=10))

    def test_reflection_only_on_a_development_server_or_when_asked(self):
        for args, dev_tenant, offered in (([], None, False), (["--reflection"], None, True), ([], "python", True)):
            server = Server(args=args, dev_tenant=dev_tenant)
            self.addCleanup(server.stop)
            if dev_tenant:  # callers without a token act as the dev tenant, for reflection too
                self.assertEqual(len(self.list_services(server)), 1)
                continue
            with self.assertRaises(grpc.RpcError) as unknown:  # the API wants a token
                server.jobs.ListJobs(job_pb2.ListJobsRequest(), timeout=10)
            self.assertEqual(unknown.exception.code(), grpc.StatusCode.UNAUTHENTICATED)
            with self.assertRaises(grpc.RpcError) as refused:
                self.list_services(server)
            if not offered:
                self.assertEqual(refused.exception.code(), grpc.StatusCode.UNIMPLEMENTED)
                continue
            # Offered, but like the API only to a caller with a token.
            self.assertEqual(refused.exception.code(), grpc.StatusCode.CANCELLED)
            self.assertIn("grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo refused: authorization",
                          server.server_log())
            secret = token(server.url, "create", "--tenant", "reflecting")
            self.assertEqual(len(self.list_services(server, [("authorization", "Bearer " + secret)])), 1)
            with self.assertRaises(grpc.RpcError) as revoked:
                self.list_services(server, [("authorization", "Bearer bst_wrong")])
            self.assertEqual(revoked.exception.code(), grpc.StatusCode.CANCELLED)


class KilledServerTest(unittest.TestCase):
    """Two servers on one database; the one running a job is killed outright (SIGKILL: no
    give-back) in its register stage, once it has stored a registered batch. The other reaps the
    job once its lease expires, takes up the batches the killed one stored (jobs that resume) and
    finishes it with the poses of an undisturbed run. A 5 s lease keeps the test short."""

    def setUp(self):
        self.first = Server(args=["--lease-seconds", "5"])
        self.addCleanup(self.first.stop)

    def test_the_other_server_finishes_the_job_of_a_killed_one(self):
        survey_id = ready_survey(self.first.surveys, "killed")
        job = self.first.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="mchs"), timeout=30)
        for event in self.first.jobs.WatchJob(job_pb2.WatchJobRequest(job_id=job.id), timeout=120):
            if event.stage == "register":
                break
        # The second server starts once the first holds the job, so that it is the first's to lose.
        second = Server(args=["--lease-seconds", "5"], db=self.first.db)
        self.addCleanup(second.stop)
        stored = f"SELECT count(*) FROM job_checkpoints WHERE job_id = {job.id}"
        deadline = time.monotonic() + 60
        while int(psql(self.first.url, stored)) == 0:
            self.assertLess(time.monotonic(), deadline, "no registered batch stored in 60 s")
            time.sleep(0.05)
        self.first.channel.close()
        self.first.process.kill()
        self.first.process.wait(timeout=30)
        self.first.process.stdout.close()
        killed = time.monotonic()
        ended = final_state(second, job.id)
        log = second.server_log()
        self.assertEqual(ended.state, job_pb2.SUCCEEDED, ended.error + log)
        self.assertEqual(ended.attempts, 2, log)
        self.assertIn(f"job {job.id}: claimed by", log)
        self.assertRegex(log, rf"job {job.id}: took up [1-9][0-9]* of [0-9]+ registered batches from an earlier attempt")
        self.assertEqual(psql(self.first.url, stored), "0", "the checkpoints go once the results are stored")
        attempt = re.search(rf"job {job.id}: succeeded in ([0-9.]+) s", log)
        print(f"\nkilled server's job finished by the other {time.monotonic() - killed:.1f} s after the kill"
              f" (its attempt took {attempt.group(1) if attempt else '?'} s)", flush=True)
        again = second.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="mchs"), timeout=30)
        self.assertEqual(final_state(second, again.id).state, job_pb2.SUCCEEDED, second.server_log())
        self.assertEqual(poses(second, job.id), poses(second, again.id))


if __name__ == "__main__":
    unittest.main(verbosity=2)

#!/usr/bin/env python3
"""Load on loopback, bounded in time and count: 8 clients upload files, 8 read tiles over gRPC
and 8 read XYZ tiles over HTTP at once for LOAD_SECONDS (default 60) while two `mchs` jobs run
on the server's two workers. No call may
fail, both jobs must succeed, and the server's resident memory must stay under LOAD_MAX_RSS_MB
(default 3000), during the load and after the jobs. Prints throughput and latency
percentiles (docs/service.md's figures come from here). The same environment as
service_api_test.py (set by ctest)."""
import hashlib
import http.client
import json
import math
import random
import threading
import time
import unittest

import grpc

from http_api_test import HttpServer
from reliability_test import final_state
from service_api_test import ENV, job_pb2, map_pb2, read, ready_survey, survey_pb2, upload_requests

SECONDS = float(ENV.get("LOAD_SECONDS", "60"))
MAX_RSS_MB = float(ENV.get("LOAD_MAX_RSS_MB", "3000"))
UPLOADERS = READERS = XYZ_READERS = 8


def rss_mb(pid):
    with open(f"/proc/{pid}/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:")) / 1024


def percentiles(seconds):
    ordered = sorted(seconds)
    pick = lambda q: ordered[min(len(ordered) - 1, int(q * len(ordered)))] * 1000  # noqa: E731
    return f"p50 {pick(0.5):.0f} ms, p90 {pick(0.9):.0f} ms, p99 {pick(0.99):.0f} ms, max {ordered[-1] * 1000:.0f} ms"


class LoadTest(unittest.TestCase):
    def setUp(self):
        self.server = HttpServer(args=["--workers", "2"])
        self.addCleanup(self.server.stop)

    def uploader(self, index, until, latencies, errors):
        """Creates a survey, uploads nav.csv into it and deletes it, again and again."""
        surveys, data = self.server.surveys, self.nav
        rounds = 0
        while time.monotonic() < until:
            rounds += 1
            try:
                started = time.monotonic()
                survey_id = surveys.CreateSurvey(survey_pb2.CreateSurveyRequest(name=f"load {index}.{rounds}"), timeout=60).id
                status = surveys.UploadFile(upload_requests(survey_id, "nav.csv", data), timeout=60)
                latencies.append(time.monotonic() - started)
                if not status.complete or status.sha256 != self.nav_sha:
                    errors.append(f"upload {index}.{rounds}: {status}")
                surveys.DeleteSurvey(survey_pb2.DeleteSurveyRequest(survey_id=survey_id), timeout=60)
            except grpc.RpcError as error:
                errors.append(f"uploader {index}: {error.code()} {error.details()}")

    def reader(self, tiles, until, latencies, sizes, errors):
        rng = random.Random(len(latencies))
        while time.monotonic() < until:
            tile = rng.choice(tiles)
            try:
                started = time.monotonic()
                chunks = list(self.server.maps.GetTile(map_pb2.GetTileRequest(job_id=self.job, level=tile.level, col=tile.col,
                                                                               row=tile.row, format=map_pb2.GEOTIFF), timeout=60))
                latencies.append(time.monotonic() - started)
                sizes.append(sum(len(chunk.data) for chunk in chunks))
            except grpc.RpcError as error:
                errors.append(f"tile {tile.level}/{tile.col}/{tile.row}: {error.code()} {error.details()}")

    def xyz_tiles(self):
        """(z, x, y) of every XYZ tile over the map at the TileJSON's six finest native zooms."""
        connection = self.server.connection()
        connection.request("GET", f"/v1/jobs/{self.job}/tiles.json")
        tilejson = json.loads(connection.getresponse().read())
        west, south, east, north = tilejson["bounds"]
        tiles = []
        for z in range(tilejson["maxzoom"] - 7, tilejson["maxzoom"] - 1):
            n = 2 ** z
            def xy(lon, lat):
                phi = math.radians(lat)
                return int((lon + 180) / 360 * n), int((1 - math.log(math.tan(phi) + 1 / math.cos(phi)) / math.pi) / 2 * n)
            (x0, y0), (x1, y1) = xy(west, north), xy(east, south)
            tiles += [(z, x, y) for x in range(x0, x1 + 1) for y in range(y0, y1 + 1)]
        return tiles

    def xyz_reader(self, tiles, until, latencies, errors):
        """XYZ tiles over HTTP, one keep-alive connection, as a map viewer fetches them."""
        rng = random.Random(len(latencies) + 100)
        connection = self.server.connection()
        while time.monotonic() < until:
            z, x, y = rng.choice(tiles)
            try:
                started = time.monotonic()
                connection.request("GET", f"/v1/jobs/{self.job}/tiles/{z}/{x}/{y}.png")
                reply = connection.getresponse()
                body = reply.read()
                latencies.append(time.monotonic() - started)
                if reply.status != 200 or not body.startswith(b"\x89PNG"):
                    errors.append(f"xyz tile {z}/{x}/{y}: HTTP {reply.status}")
            except (OSError, http.client.HTTPException) as error:
                errors.append(f"xyz tile {z}/{x}/{y}: {error}")
                connection = self.server.connection()

    def test_uploads_and_tile_reads_while_two_jobs_run(self):
        s = self.server
        self.nav = read("nav.csv")
        self.nav_sha = hashlib.sha256(self.nav).digest()
        survey_id = ready_survey(s.surveys, "load")
        first = s.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="odometry"), timeout=30)
        self.assertEqual(final_state(s, first.id).state, job_pb2.SUCCEEDED, s.server_log())
        self.job = first.id
        tiles = [t for t in s.maps.GetMapInfo(map_pb2.GetMapInfoRequest(job_id=first.id), timeout=30).tiles
                 if map_pb2.GEOTIFF in t.formats]
        self.assertTrue(tiles)
        running = [s.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=survey_id, configuration="mchs"), timeout=30).id
                   for _ in range(2)]

        xyz_tiles = self.xyz_tiles()
        self.assertTrue(xyz_tiles)
        errors, upload_latency, tile_latency, tile_bytes, rss = [], [], [], [], [rss_mb(s.process.pid)]
        xyz_latency = []
        until = time.monotonic() + SECONDS
        threads = [threading.Thread(target=self.uploader, args=(i, until, upload_latency, errors)) for i in range(UPLOADERS)]
        threads += [threading.Thread(target=self.reader, args=(tiles, until, tile_latency, tile_bytes, errors))
                    for _ in range(READERS)]
        threads += [threading.Thread(target=self.xyz_reader, args=(xyz_tiles, until, xyz_latency, errors))
                    for _ in range(XYZ_READERS)]
        for thread in threads:
            thread.start()
        while time.monotonic() < until:
            rss.append(rss_mb(s.process.pid))
            time.sleep(1)
        for thread in threads:
            thread.join()
        states = [s.jobs.GetJob(job_pb2.GetJobRequest(job_id=job), timeout=30).state for job in running]
        jobs_ran = all(state in (job_pb2.RUNNING, job_pb2.SUCCEEDED) for state in states)
        for job in running:
            self.assertEqual(final_state(s, job, seconds=900).state, job_pb2.SUCCEEDED, s.server_log())
        after_jobs = rss_mb(s.process.pid)

        print(f"\n{SECONDS:.0f} s, {UPLOADERS} uploaders, {READERS} tile readers and {XYZ_READERS} XYZ tile readers (HTTP), "
              f"two mchs jobs on 2 workers:\n"
              f"  uploads: {len(upload_latency)} of {len(self.nav) / 1e6:.2f} MB "
              f"({len(upload_latency) / SECONDS:.1f}/s, {len(upload_latency) * len(self.nav) / 1e6 / SECONDS:.1f} MB/s); "
              f"create + upload {percentiles(upload_latency)}\n"
              f"  tiles: {len(tile_latency)} GeoTIFF tiles, mean {sum(tile_bytes) / max(1, len(tile_bytes)) / 1e3:.0f} kB "
              f"({len(tile_latency) / SECONDS:.1f}/s); {percentiles(tile_latency)}\n"
              f"  XYZ tiles over HTTP: {len(xyz_latency)} of {len(xyz_tiles)} distinct "
              f"({len(xyz_latency) / SECONDS:.1f}/s); {percentiles(xyz_latency)}\n"
              f"  server RSS: {rss[0]:.0f} MB at the start, {max(rss):.0f} MB at most, {after_jobs:.0f} MB after the jobs; "
              f"errors: {len(errors)}", flush=True)
        self.assertEqual(errors, [])
        self.assertTrue(jobs_ran, f"the jobs were not running during the load: {states}")
        self.assertGreater(len(upload_latency), UPLOADERS)
        self.assertGreater(len(tile_latency), READERS)
        self.assertGreater(len(xyz_latency), XYZ_READERS)
        self.assertLess(max(rss + [after_jobs]), MAX_RSS_MB)
        self.assertIsNone(s.process.poll(), "the server died:\n" + s.server_log())


if __name__ == "__main__":
    unittest.main(verbosity=2)

#!/usr/bin/env python3
"""The HTTP endpoint (`bathyslam-server --http`) against a real server and PostgreSQL: GDAL reads
a job's map through /vsicurl/ with the bearer token in a few range requests, the bytes are the
gRPC API's; ranges, paths and every route x caller answer as they should, and no refusal changes
the database. The same environment as service_api_test.py (set by ctest)."""
import http.client
import json
import os
import re
import time
import unittest
import urllib.parse

import numpy
from osgeo import gdal, osr

from service_api_test import STUBS, Server, database_fingerprint, job_pb2, map_pb2, restart_asking_for_tokens

import bathyslam  # noqa: E402  (the Python client, on the path service_api_test puts)

gdal.UseExceptions()


def srs(epsg):
    ref = osr.SpatialReference()
    ref.ImportFromEPSG(epsg)
    ref.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    return ref


class HttpServer(Server):
    """A Server with the HTTP endpoint on a free port: `self.http` is its base URL."""

    def start(self):
        if "--http" not in self.args:
            self.args += ["--http", "127.0.0.1:0"]
        super().start()
        line = self.process.stdout.readline()
        match = re.search(r"http on (\S+)", line)
        if not match:
            raise RuntimeError("no HTTP endpoint: " + line + self.server_log())
        self.http = match.group(1)

    def connection(self, timeout=60):
        """A new HTTP connection to the endpoint."""
        url = urllib.parse.urlsplit(self.http)
        return http.client.HTTPConnection(url.hostname, url.port, timeout=timeout)


class HttpApiTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # The owner's survey and job are made on a development server, which then restarts
        # asking every caller for a token (as isolation_test.py does).
        cls.server = HttpServer(dev_tenant="owner")
        s = cls.server
        with bathyslam.Client(s.address) as client:  # the Python client
            cls.survey = client.upload(os.environ["SMALL_BUNDLE"])
            cls.job = client.submit(cls.survey, "mchs")
            client.watch(cls.job)
            with open(client.download_map(cls.job, os.path.join(STUBS, "grpc_map.tif")), "rb") as f:
                cls.cog = f.read()
        cls.tokens = restart_asking_for_tokens(s)

    @classmethod
    def tearDownClass(cls):
        if os.environ.get("SHOW_SERVER_LOG"):
            print(cls.server.server_log())
        cls.server.stop()

    def get(self, path, who="owner", headers=None):
        """(status, headers, body) of GET `path` as `who` ("no token" sends none)."""
        connection = self.server.connection()
        headers = dict(headers or {})
        if who != "no token":
            headers["Authorization"] = "Bearer " + self.tokens[who]
        connection.request("GET", path, headers=headers)
        response = connection.getresponse()
        body = response.read()
        connection.close()
        return response.status, response.headers, body

    def served(self, path):
        """(requests, bytes) the server's log shows for GETs of `path`."""
        lines = re.findall(r"http (GET|HEAD) " + re.escape(path) + r" \d+ (\d+) bytes", self.server.server_log())
        return len(lines), sum(int(size) for method, size in lines if method == "GET")  # HEAD sends no body

    def test_gdal_reads_the_map_by_range_requests(self):
        path = f"/v1/jobs/{self.job}/map.tif"
        options = {"GDAL_HTTP_HEADERS": "Authorization: Bearer " + self.tokens["owner"],
                   "GDAL_DISABLE_READDIR_ON_OPEN": "EMPTY_DIR", "VSI_CACHE": "FALSE"}
        for key, value in options.items():
            gdal.SetConfigOption(key, value)
        try:
            mine = gdal.Open(os.path.join(STUBS, "grpc_map.tif"))
            before = self.served(path)
            remote = gdal.Open("/vsicurl/" + self.server.http + path)
            info = gdal.Info(remote, format="json")
            self.assertEqual(info["driverShortName"], "GTiff")
            self.assertEqual(info["size"], [mine.RasterXSize, mine.RasterYSize])
            self.assertEqual(remote.GetGeoTransform(), mine.GetGeoTransform())
            self.assertEqual(remote.GetRasterBand(1).ReadRaster(0, 0, 1, 1), mine.GetRasterBand(1).ReadRaster(0, 0, 1, 1))
            # A window of a quarter of the map, as gdal_translate -srcwin reads it.
            w, h = max(1, mine.RasterXSize // 2), max(1, mine.RasterYSize // 2)
            out = os.path.join(STUBS, "window.tif")
            gdal.Translate(out, remote, srcWin=[w // 2, h // 2, w, h])
            window = gdal.Open(out)
            for band in range(1, mine.RasterCount + 1):
                self.assertEqual(window.GetRasterBand(band).ReadRaster(),
                                 mine.GetRasterBand(band).ReadRaster(w // 2, h // 2, w, h), f"band {band}")
            remote = window = None
            after = self.served(path)
            requests, sent = after[0] - before[0], after[1] - before[1]
            # `small`'s map is one 512 x 512 block: every byte is read, but each once, by ranges
            # (docs/http.md measures a window of the `lake` map).
            self.assertLessEqual(requests, 4, f"{requests} requests for info and a window")
            self.assertLessEqual(sent, len(self.cog), f"{sent} bytes sent of {len(self.cog)}: read more than once")
            self.assertRegex(self.server.server_log(), r"http GET " + re.escape(path) + r" 206 ")
            print(f"GDAL: info + {w}x{h} window of a {len(self.cog)}-byte COG in {requests} requests, {sent} bytes")
        finally:
            for key in options:
                gdal.SetConfigOption(key, None)

    def test_ranges(self):
        path, size = f"/v1/jobs/{self.job}/map.tif", len(self.cog)
        status, headers, body = self.get(path)
        self.assertEqual((status, body), (200, self.cog))
        self.assertEqual(headers["Accept-Ranges"], "bytes")
        etag = headers["ETag"]
        cases = {"bytes=0-99": (206, 0, 100), "bytes=-1": (206, size - 1, 1), "bytes=10-": (206, 10, size - 10),
                 f"bytes=100-{size * 2}": (206, 100, size - 100)}
        for header, (code, offset, length) in cases.items():
            status, headers, body = self.get(path, headers={"Range": header})
            self.assertEqual(status, code, header)
            self.assertEqual(body, self.cog[offset:offset + length], header)
            self.assertEqual(headers["Content-Range"], f"bytes {offset}-{offset + length - 1}/{size}", header)
        # Several ranges, overlapping or hundreds, are answered with the whole file; a header
        # longer than the library's 8 KiB is refused.
        for header in ("bytes=0-9,5-20", "bytes=" + ",".join(f"{2 * k}-{2 * k}" for k in range(500))):
            status, _, body = self.get(path, headers={"Range": header})
            self.assertEqual((status, len(body)), (200, size), header[:40])
        status, _, body = self.get(path, headers={"Range": "bytes=" + ",".join(f"{9 * k}-{9 * k}" for k in range(1000))})
        self.assertEqual(status, 400)
        self.assertIn("too long", json.loads(body)["error"])
        for header in (f"bytes={size}-", f"bytes={size + 10}-{size + 20}", "bytes=-0"):
            status, headers, body = self.get(path, headers={"Range": header})
            self.assertEqual(status, 416, header)
            self.assertEqual(headers["Content-Range"], f"bytes */{size}", header)
            self.assertIn("beyond", json.loads(body)["error"], header)
        status, _, body = self.get(path, headers={"Range": "bytes=abc"})
        self.assertEqual(status, 416)
        self.assertIn("Range", json.loads(body)["error"])
        status, _, body = self.get(path, headers={"If-None-Match": etag})
        self.assertEqual((status, body), (304, b""))

    def test_lists_job_report_and_plots(self):
        status, _, body = self.get("/v1/surveys")
        self.assertEqual(status, 200)
        self.assertEqual([s["id"] for s in json.loads(body)["surveys"]], [self.survey])
        status, _, body = self.get("/v1/jobs")
        jobs = json.loads(body)["jobs"]
        self.assertIn((self.job, "succeeded", "mchs"), [(j["id"], j["state"], j["configuration"]) for j in jobs])
        self.assertEqual([j["id"] for j in jobs], sorted((j["id"] for j in jobs), reverse=True), "newest first")
        status, _, body = self.get(f"/v1/jobs?survey_id={self.survey}&page_size=1")
        page = json.loads(body)
        self.assertEqual([j["id"] for j in page["jobs"]], [jobs[0]["id"]])
        if len(jobs) > 1:  # another test's job too: the next page starts after this one
            status, _, body = self.get(f"/v1/jobs?survey_id={self.survey}&page_size=1&page_token={page['next_page_token']}")
            self.assertEqual([j["id"] for j in json.loads(body)["jobs"]], [jobs[1]["id"]])
        status, _, body = self.get(f"/v1/jobs/{self.job}/report.json")
        self.assertEqual(status, 200)
        report = json.loads(body)
        self.assertEqual(report["configuration"], "mchs")
        self.assertIn("consistency_error_m", report)
        reply = self.server.jobs.GetReport(job_pb2.GetReportRequest(job_id=self.job), timeout=60,
                                           metadata=[("authorization", "Bearer " + self.tokens["owner"])])
        for plot in reply.plots:
            status, headers, body = self.get(f"/v1/jobs/{self.job}/plots/{plot.name}")
            self.assertEqual((status, headers["Content-Type"], body), (200, "image/png", plot.png), plot.name)
        self.assertGreater(len(reply.plots), 0)
        status, _, body = self.get(f"/v1/jobs/{self.job}/map.bag")
        self.assertEqual((status, body[:8]), (200, b"\x89HDF\r\n\x1a\n"))
        status, _, body = self.get(f"/v1/jobs/{self.job}/trajectory.geojson")
        kinds = [f["properties"]["kind"] for f in json.loads(body)["features"]]
        self.assertEqual((status, kinds[:2]), (200, ["dead_reckoning", "corrected"]))
        accepted_loops = sum(1 for c in report["registrations"] if c["type"] == "loop" and c["accepted"])
        self.assertEqual(kinds.count("loop_closure"), accepted_loops)
        # The corrected GSF by ranges, across the boundary of its stored chunks (1 MiB).
        owner = [("authorization", "Bearer " + self.tokens["owner"])]
        gsf = b"".join(c.data for c in self.server.maps.GetMap(map_pb2.GetMapRequest(job_id=self.job, format=map_pb2.GSF),
                                                                 timeout=120, metadata=owner))
        for first, last in ((0, 99), ((1 << 20) - 500, (1 << 20) + 499), (len(gsf) - 10, len(gsf) + 10)):
            status, _, body = self.get(f"/v1/jobs/{self.job}/corrected.gsf", headers={"Range": f"bytes={first}-{last}"})
            self.assertEqual((status, body), (206, gsf[first:last + 1]), (first, last))

    def test_gdal_reads_the_xyz_tiles(self):
        """GDAL's WMS driver reads the unshaded XYZ tiles over the map; turned back into elevation
        through the TileJSON's ramp they agree with the COG warped to Web Mercator."""
        status, _, body = self.get(f"/v1/jobs/{self.job}/tiles.json")
        self.assertEqual(status, 200)
        tilejson = json.loads(body)
        west, south, east, north = tilejson["bounds"]
        self.assertTrue(-180 < west < east < 180 and -85 < south < north < 85, tilejson["bounds"])
        lo, hi = tilejson["bathyslam"]["elevation_range_m"]
        ramp = numpy.array([[int(c[k:k + 2], 16) for k in (1, 3, 5)] for c in tilejson["bathyslam"]["ramp"]], float)
        level = tilejson["maxzoom"] - 2  # pixels as fine as the map's cells
        world = 20037508.342789244
        url = tilejson["tiles"][0].replace("{z}", "${z}").replace("{x}", "${x}").replace("{y}", "${y}") + "?shade=0"
        wms = (f"<GDAL_WMS><Service name='TMS'><ServerUrl>{url}</ServerUrl></Service><DataWindow>"
               f"<UpperLeftX>{-world}</UpperLeftX><UpperLeftY>{world}</UpperLeftY><LowerRightX>{world}</LowerRightX>"
               f"<LowerRightY>{-world}</LowerRightY><TileLevel>{level}</TileLevel><TileCountX>1</TileCountX>"
               "<TileCountY>1</TileCountY><YOrigin>top</YOrigin></DataWindow><Projection>EPSG:3857</Projection>"
               "<BlockSizeX>256</BlockSizeX><BlockSizeY>256</BlockSizeY><BandsCount>4</BandsCount>"
               "<ZeroBlockHttpCodes>404</ZeroBlockHttpCodes><Cache/></GDAL_WMS>")
        gdal.SetConfigOption("GDAL_HTTP_HEADERS", "Authorization: Bearer " + self.tokens["owner"])
        try:
            tiles = gdal.Open(wms)
            pixel = 2 * world / tiles.RasterXSize
            to_mercator = osr.CoordinateTransformation(srs(4326), srs(3857))
            (x0, y1, _), (x1, y0, _) = (to_mercator.TransformPoint(west, south), to_mercator.TransformPoint(east, north))
            col0, row0 = int((x0 + world) / pixel), int((world - y0) / pixel)
            cols, rows = int((x1 + world) / pixel) + 1 - col0, int((world - y1) / pixel) + 1 - row0
            rgba = tiles.ReadAsArray(col0, row0, cols, rows)
        finally:
            gdal.SetConfigOption("GDAL_HTTP_HEADERS", None)
        local = os.path.join(STUBS, "grpc_map.tif")
        bounds = (-world + col0 * pixel, world - (row0 + rows) * pixel, -world + (col0 + cols) * pixel, world - row0 * pixel)
        reference = gdal.Warp("/vsimem/xyz_reference.tif", local, dstSRS="EPSG:3857", outputBounds=bounds, width=cols,
                              height=rows, resampleAlg="near")  # held: a band outlives no dataset
        warped = reference.GetRasterBand(1).ReadAsArray()
        rgb = rgba[:3].transpose(1, 2, 0).reshape(-1, 3).astype(float)
        index = ((rgb[:, None, :] - ramp[None, :, :]) ** 2).sum(axis=2).argmin(axis=1).reshape(rows, cols)
        from_tiles = numpy.where(rgba[3] > 0, lo + (hi - lo) * index / 255.0, numpy.nan)
        both = numpy.isfinite(from_tiles) & numpy.isfinite(warped) & (warped >= lo) & (warped <= hi)
        self.assertGreater(both.sum(), 1000)
        agree = numpy.abs(from_tiles[both] - warped[both]) <= 1.5 * (hi - lo) / 255
        self.assertGreater(agree.mean(), 0.95, f"{agree.mean():.3f} of {both.sum()} pixels within the ramp's step")
        covered = numpy.isfinite(from_tiles) == numpy.isfinite(warped)
        self.assertGreater(covered.mean(), 0.97, "where the tiles have data and the COG has")
        print(f"XYZ level {level}: {both.sum()} pixels, {agree.mean():.4f} within 1.5 ramp steps ({(hi - lo) / 255:.3f} m)")

    def test_tile_coordinates(self):
        for path, code, words in ((f"/v1/jobs/{self.job}/tiles/40/0/0.png", 400, "z must be within"),
                                  (f"/v1/jobs/{self.job}/tiles/3/-1/0.png", 400, "x and y must be within"),
                                  (f"/v1/jobs/{self.job}/tiles/3/8/0.png", 400, "x and y must be within"),
                                  (f"/v1/jobs/{self.job}/tiles/12/0/0.png", 404, "outside job"),
                                  (f"/v1/jobs/{self.job}/tiles/99999999999/0/0.png", 400, "not a tile coordinate")):
            status, _, body = self.get(path)
            self.assertEqual(status, code, path)
            self.assertIn(words, json.loads(body)["error"], path)
        status, headers, body = self.get(f"/v1/jobs/{self.job}/tiles/0/0/0.png")
        self.assertEqual((status, headers["Content-Type"], body[:4]), (200, "image/png", b"\x89PNG"))

    def events(self, job, last_event_id=None):
        """The job's server-sent events until the stream ends: [(id, name, data)]."""
        connection = self.server.connection(timeout=120)
        headers = {"Authorization": "Bearer " + self.tokens["owner"]}
        if last_event_id is not None:
            headers["Last-Event-ID"] = str(last_event_id)
        connection.request("GET", f"/v1/jobs/{job}/events", headers=headers)
        response = connection.getresponse()
        self.assertEqual((response.status, response.headers["Content-Type"]), (200, "text/event-stream"))
        events, fields = [], {}
        for raw in response:
            line = raw.decode().rstrip("\n")
            if line == "" and fields:
                events.append((int(fields.get("id", 0)), fields["event"], json.loads(fields["data"])))
                fields = {}
            elif line and not line.startswith(":"):
                key, _, value = line.partition(": ")
                fields[key] = value
        connection.close()
        return events

    def test_job_progress_as_server_sent_events(self):
        owner = [("authorization", "Bearer " + self.tokens["owner"])]
        job = self.server.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=self.survey, configuration="odometry"),
                                         timeout=30, metadata=owner).id
        events = self.events(job)
        progress = [e for e in events if e[1] == "progress"]
        self.assertGreater(len(progress), 3)
        self.assertEqual([e[0] for e in progress], sorted({e[0] for e in progress}), "ids rise, none twice")
        self.assertEqual(events[-1][1], "end")
        self.assertEqual((events[-1][2]["id"], events[-1][2]["state"]), (job, "succeeded"))
        self.assertIn("store", {e[2]["stage"] for e in progress})
        # Resumed after an event: exactly the ones after it, then the end again.
        middle = progress[len(progress) // 2][0]
        again = self.events(job, last_event_id=middle)
        self.assertEqual([e[0] for e in again if e[1] == "progress"], [e[0] for e in progress if e[0] > middle])
        self.assertEqual(again[-1][1], "end")

    def test_a_tenant_cannot_hold_every_thread(self):
        # A server whose tenants may each have 3 requests in progress and no worker, so that a
        # job stays queued and its event streams stay open: each holds one of its tenant's slots.
        s = self.server
        s.halt()
        s.args = ["--workers", "0", "--max-http-requests", "3"]
        s.start()
        owner = [("authorization", "Bearer " + self.tokens["owner"])]
        job = s.jobs.SubmitJob(job_pb2.SubmitJobRequest(survey_id=self.survey, configuration="odometry"),
                               timeout=30, metadata=owner).id
        streams = []
        try:
            for _ in range(3):
                connection = s.connection()
                connection.request("GET", f"/v1/jobs/{job}/events", headers={"Authorization": "Bearer " + self.tokens["owner"]})
                response = connection.getresponse()
                self.assertEqual(response.status, 200)
                streams.append(connection)
            before = database_fingerprint(s.url)
            status, headers, body = self.get("/v1/surveys")
            self.assertEqual((status, headers["Retry-After"]), (429, "1"))
            self.assertIn("3 HTTP requests in progress on this server", json.loads(body)["error"])
            self.assertEqual(database_fingerprint(s.url), before)
            self.assertEqual(self.get("/v1/surveys", "another tenant")[0], 200, "another tenant is served")
            # A stream closed gives its slot back once the server sees the client gone (its
            # streams look every 2 s).
            streams.pop().close()
            statuses = []
            for _ in range(40):
                statuses.append(self.get("/v1/surveys")[0])
                if statuses[-1] == 200:
                    break
                time.sleep(0.25)
            self.assertEqual(statuses[-1], 200, statuses)
        finally:
            for connection in streams:
                connection.close()
            s.jobs.CancelJob(job_pb2.CancelJobRequest(job_id=job), timeout=30, metadata=owner)
            s.halt()
            s.args = ["--http", "127.0.0.1:0"]
            s.start()

    def test_malformed_paths(self):
        for path, code in ((f"/v1/jobs/{self.job}/../../../etc/passwd", 404), ("/v1/jobs/0", 400),
                           ("/v1/jobs/99999999999999999999999/map.tif", 400), ("/v1/jobs/x/map.tif", 404),
                           (f"/v1/jobs/{self.job}/plots/..%2F..%2Fpasswd.png", 404), ("/v1/surveys?page_size=5000", 400),
                           ("/v1/jobs?page_token=abc", 400), ("/nothing", 404)):
            status, headers, body = self.get(path)
            self.assertEqual(status, code, path)
            self.assertEqual(headers["Content-Type"], "application/json", path)
            self.assertTrue(json.loads(body)["error"], path)

    def test_bytes_that_are_not_utf8_and_static_files(self):
        # The decoded path and the Range header go into the JSON error: not UTF-8, they are
        # replaced, and the server (whose error handler runs outside the library's try) lives.
        status, _, body = self.get("/%FF%FE")
        self.assertEqual(status, 404)
        self.assertIn("no such resource", json.loads(body)["error"])
        status, _, body = self.get(f"/v1/jobs/{self.job}/map.tif", headers={"Range": "bytes=\xff"})
        self.assertEqual(status, 416)
        self.assertIn("Range", json.loads(body)["error"])
        self.assertEqual(self.get("/v1/surveys")[0], 200)
        status, headers, body = self.get("/static/app.js", who="no token", headers={"Range": "bytes=0-9"})
        self.assertEqual((status, headers["Content-Type"]), (200, "text/javascript; charset=utf-8"))
        self.assertGreater(len(body), 1000, "a page's file is sent whole, whatever the Range")
        status, _, body = self.get("/static/no-such-file.js", who="no token")
        self.assertEqual(status, 404)
        self.assertIn("no such resource", json.loads(body)["error"])
        status, _, body = self.get("/", who="no token")
        self.assertIn(b"<title>bathyslam</title>", body)

    def test_every_route_and_caller(self):
        routes = ["/v1/surveys", "/v1/jobs", f"/v1/jobs?survey_id={self.survey}", f"/v1/jobs/{self.job}",
                  f"/v1/jobs/{self.job}/report.json", f"/v1/jobs/{self.job}/plots/trajectory.png",
                  f"/v1/jobs/{self.job}/map.tif", f"/v1/jobs/{self.job}/map.bag", f"/v1/jobs/{self.job}/tiles.json",
                  f"/v1/jobs/{self.job}/tiles/0/0/0.png", f"/v1/jobs/{self.job}/events",
                  f"/v1/jobs/{self.job}/trajectory.geojson"]
        for route in routes:
            before = database_fingerprint(self.server.url)
            for who in ("no token", "wrong token", "revoked token"):
                status, headers, body = self.get(route, who)
                self.assertEqual(status, 401, (route, who))
                self.assertEqual(headers["WWW-Authenticate"], "Bearer")
                self.assertIn("authorization", json.loads(body)["error"])
            status, _, body = self.get(route, "another tenant")
            if route in ("/v1/surveys", "/v1/jobs"):  # a list of the intruder's own: empty
                self.assertEqual((status, list(json.loads(body).values())[0]), (200, []), route)
            else:
                self.assertEqual(status, 404, route)
                self.assertRegex(json.loads(body)["error"], r"no (survey|job) \d+", route)
            self.assertEqual(database_fingerprint(self.server.url), before, route)
            status, _, body = self.get(route, "owner")
            self.assertEqual(status, 200, (route, body[:200]))


if __name__ == "__main__":
    unittest.main()

#!/usr/bin/env python3
"""The web page (server/http/web) in headless Chromium, driven over the DevTools protocol: a
wrong token is refused on the page; signed in with a real one it lists the survey and the job,
shows the job's progress while it runs, and when it ends the report, the map's tiles, the
trajectories and the loop closures; a screenshot of the map is not blank. The same environment
as service_api_test.py (set by ctest)."""
import base64
import json
import os
import re
import shutil
import subprocess
import tempfile
import time
import unittest
import urllib.request

import numpy
import websocket
from osgeo import gdal

from http_api_test import HttpServer
from service_api_test import ENV, token

import bathyslam  # noqa: E402  (on the path service_api_test puts)

gdal.UseExceptions()


class Browser:
    """Headless Chromium showing `url`, and its page's DevTools connection."""

    def __init__(self, url):
        self.profile = tempfile.mkdtemp(prefix="bathyslam-chromium-")
        self.process = subprocess.Popen(
            ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--hide-scrollbars",
             "--window-size=1280,1400",
             "--remote-debugging-port=0", f"--user-data-dir={self.profile}", url],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        for line in self.process.stderr:
            match = re.search(r"DevTools listening on ws://([^/]+)/", line)
            if match:
                break
        else:
            raise RuntimeError("chromium did not start")
        pages = json.load(urllib.request.urlopen(f"http://{match.group(1)}/json/list", timeout=30))
        self.socket = websocket.create_connection(next(p for p in pages if p["type"] == "page")["webSocketDebuggerUrl"],
                                                  timeout=60)
        self.next_id = 0

    def call(self, method, **params):
        self.next_id += 1
        self.socket.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            reply = json.loads(self.socket.recv())
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        return result["result"].get("value")

    def wait_for(self, expression, seconds=180, what=""):
        """Polls `expression` until truthy; returns its value."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            value = self.evaluate(expression)
            if value:
                return value
            time.sleep(0.2)
        error = self.evaluate("document.getElementById('error').textContent")
        raise AssertionError(f"{what or expression} not within {seconds} s; the page's error: {error!r}")

    def close(self):
        self.socket.close()
        self.process.kill()
        self.process.wait()
        shutil.rmtree(self.profile, ignore_errors=True)


class WebPageTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = HttpServer(dev_tenant="owner")
        cls.token = token(cls.server.url, "create", "--tenant", "owner")
        with bathyslam.Client(cls.server.address, cls.token) as client:
            cls.survey = client.upload(ENV["SMALL_BUNDLE"])

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def test_a_wrong_token_is_refused_on_the_page(self):
        browser = Browser(f"{self.server.http}/#token=bst_{'0' * 40}")
        try:
            error = browser.wait_for("document.getElementById('error').textContent", 60, "an error shown")
            self.assertIn("401", error)
            self.assertIn("unknown or revoked token", error)
            self.assertEqual(browser.evaluate("document.querySelectorAll('#jobs tbody tr').length"), 0)
        finally:
            browser.close()

    def test_a_job_from_progress_to_map(self):
        with bathyslam.Client(self.server.address, self.token) as client:
            job = client.submit(self.survey, "mchs")
        browser = Browser(f"{self.server.http}/#token={self.token}&job={job}")
        try:
            browser.wait_for("document.body.dataset.signedIn === 'true'", 60, "signed in")
            surveys = browser.evaluate("[...document.querySelectorAll('#surveys tbody tr')].map(r => r.cells[1].textContent)")
            self.assertIn("small-seed1-paper", surveys)
            row = f"document.getElementById('job-row-{job}')"
            # Progress while it runs: the bar moves off zero before the job ends.
            progress = browser.wait_for(f"{row} && {row}.dataset.state !== 'succeeded' && "
                                        f"{row}.querySelector('progress').value > 0 && "
                                        f"[{row}.cells[3].textContent, {row}.querySelector('progress').value]",
                                        180, "progress shown")
            self.assertRegex(progress[0], r"running · \w+")
            browser.wait_for(f"{row}.dataset.state === 'succeeded'", 300, "the job finished")
            browser.wait_for("document.body.dataset.jobState === 'succeeded' && "
                             "document.getElementById('report').dataset.loaded === 'true' && "
                             "document.body.dataset.tilesLoaded === 'true'", 120, "report and tiles")
            dom = browser.evaluate("""({
                title: document.getElementById('job-title').textContent,
                tables: [...document.querySelectorAll('#report table caption')].map(c => c.textContent),
                plots: document.querySelectorAll('#report img').length,
                tiles: document.querySelectorAll('#map .leaflet-tile-loaded').length,
                tracks: document.querySelectorAll('#map path.leaflet-interactive').length,
                loops: Number(document.getElementById('map').dataset.loops),
                downloads: [...document.querySelectorAll('#downloads a')].map(a => a.textContent),
                map: document.getElementById('map').getBoundingClientRect().toJSON()})""")
            self.assertIn(f"Job {job}: mchs", dom["title"])
            self.assertEqual(dom["tables"], ["Consistency of overlapping soundings", "Trajectory against the reference"])
            self.assertGreaterEqual(dom["plots"], 3)
            self.assertGreater(dom["tiles"], 0)
            self.assertEqual(dom["tracks"], 2 + dom["loops"], "dead reckoning, corrected and each loop closure")
            self.assertGreater(dom["loops"], 0)
            self.assertEqual(dom["downloads"], ["map (COG)", "BAG", "corrected GSF", "report"])
            shot = browser.call("Page.captureScreenshot", format="png",
                                clip={**{k: dom["map"][k] for k in ("x", "y", "width", "height")}, "scale": 1})
            png = base64.b64decode(shot["data"])
            with open(os.path.join(tempfile.gettempdir(), f"bathyslam-web-page-{os.getpid()}.png"), "wb") as f:
                f.write(png)  # for a person to look at when this fails
            gdal.FileFromMemBuffer("/vsimem/map_shot.png", png)
            pixels = gdal.Open("/vsimem/map_shot.png").ReadAsArray()[:3].reshape(3, -1).T
            colours = len(numpy.unique(pixels, axis=0))
            background = numpy.all(pixels == pixels[0], axis=1).mean()  # the corner's colour: no tile there
            self.assertGreater(colours, 200, "the map shows relief, not a flat colour")
            self.assertLess(background, 0.8, f"{background:.2f} of the map is its corner's colour")
            print(f"web page: {dom['tiles']} tiles, {dom['loops']} loop closures, {colours} colours in the map")
        finally:
            browser.close()


if __name__ == "__main__":
    unittest.main()

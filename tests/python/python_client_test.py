#!/usr/bin/env python3
"""The Python client (client/python/bathyslam, PYTHONPATH=build/python) against a real server:
an upload killed halfway (SIGKILL of the uploading process) resumes where the server's commit
left it, the job is submitted and watched to the end, and the map it downloads is byte for byte
the CLI's; refusals arrive as typed errors. The same environment as service_api_test.py, plus
BATHYSLAM_PYTHONPATH (set by ctest)."""
import os
import signal
import subprocess
import sys
import unittest

from service_api_test import ENV, STUBS, Server, psql  # puts build/python on the path

import bathyslam  # noqa: E402  (isort: after the path)

BUNDLE = ENV["SMALL_BUNDLE"]

# Uploads the bundle and SIGKILLs itself once half of pings.csv has been sent.
KILLED_UPLOAD = """
import os, signal, sys
sys.path.insert(0, sys.argv[1])
import bathyslam
def progress(name, sent, size):
    if name == "pings.csv" and sent >= size // 2:
        os.kill(os.getpid(), signal.SIGKILL)
bathyslam.Client(sys.argv[2]).upload(sys.argv[3], progress=progress)
"""


class PythonClientTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = Server(dev_tenant="python")

    @classmethod
    def tearDownClass(cls):
        cls.server.stop()

    def test_killed_upload_resumes_and_the_map_is_the_clis(self):
        killed = subprocess.run([sys.executable, "-c", KILLED_UPLOAD, ENV["BATHYSLAM_PYTHONPATH"], self.server.address,
                                 BUNDLE], capture_output=True, text=True, timeout=300)
        self.assertEqual(killed.returncode, -signal.SIGKILL, killed.stderr)
        pings = os.path.getsize(os.path.join(BUNDLE, "pings.csv"))
        committed = int(psql(self.server.url, "SELECT committed_bytes FROM survey_files WHERE name = 'pings.csv'") or 0)
        self.assertGreater(committed, 0, "nothing of pings.csv was committed before the kill")
        self.assertLess(committed, pings, "pings.csv was complete before the kill")

        sent = {}
        with bathyslam.Client(self.server.address) as client:
            survey = client.upload(BUNDLE, progress=lambda name, done, size: sent.setdefault(name, done))
            self.assertGreaterEqual(sent["pings.csv"], committed, "resumed from the start, not from the commit")
            self.assertNotIn("survey.json", sent, "a complete file was sent again")
            job = client.submit(survey, "mchs")
            stages = []
            finished = client.watch(job, progress=lambda stage, fraction, message: stages.append(stage))
            self.assertEqual(finished["state"], "succeeded")
            self.assertIn("register", stages)
            report = client.report(job)
            self.assertEqual(report["configuration"], "mchs")
            mine = client.download_map(job, os.path.join(STUBS, "client_map.tif"))
        cli = os.path.join(STUBS, "cli_map.tif")
        subprocess.run([ENV["BATHYSLAM"], "map", str(job), "--server", self.server.address, "--out", cli], check=True,
                       capture_output=True)
        with open(mine, "rb") as a, open(cli, "rb") as b:
            self.assertEqual(a.read(), b.read(), "the client's map differs from the CLI's")

    def test_refusals_are_typed(self):
        with bathyslam.Client(self.server.address) as client:
            with self.assertRaises(bathyslam.NotFound) as raised:
                client.report(987654)
            self.assertIn("987654", str(raised.exception))
            survey = client.upload(BUNDLE)  # the other test's survey, or a new one: ready either way
            with self.assertRaises(bathyslam.InvalidArgument):
                client.submit(survey, "no-such-configuration")
            with self.assertRaises(ValueError):
                client.upload(os.path.join(BUNDLE, "nav.csv"))
            target = os.path.join(STUBS, "refused_map.tif")
            with self.assertRaises(ValueError):
                client.download_map(1, target, format="png")
            with self.assertRaises(bathyslam.NotFound):
                client.download_map(987654, target)
            self.assertFalse(os.path.exists(target) or os.path.exists(target + ".part"), "a refused download left a file")
        with bathyslam.Client(self.server.address, token="bst_" + "0" * 40) as stranger:
            with self.assertRaises(bathyslam.Unauthenticated):
                stranger.job(1)


if __name__ == "__main__":
    unittest.main()

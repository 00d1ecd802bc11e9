#!/usr/bin/env python3
"""XYZ tiles under load (docs/http.md): CLIENTS threads fetch the tiles of a job's map over HTTP,
every tile of zooms maxzoom-8 .. maxzoom once in a shuffled order (cold: each is drawn), then
the same again (warm: from the cache); prints p50 / p99 latency and tiles per second of each
pass, and the server's peak RSS when its pid is given.
Usage: /usr/bin/python3 bench/http_tiles_load.py http://HOST:PORT JOB [--token T] [--clients 8] [--pid PID]"""
import argparse
import http.client
import json
import math
import random
import statistics
import threading
import time
import urllib.parse


def tile_range(west, south, east, north, z):
    n = 2 ** z
    def xy(lon, lat):
        phi = math.radians(lat)
        return int((lon + 180) / 360 * n), int((1 - math.log(math.tan(phi) + 1 / math.cos(phi)) / math.pi) / 2 * n)
    (x0, y0), (x1, y1) = xy(west, north), xy(east, south)
    return [(z, x, y) for x in range(x0, x1 + 1) for y in range(y0, y1 + 1)]


def run(base, job, headers, tiles, clients):
    url = urllib.parse.urlsplit(base)
    queue, lock, latencies, statuses = list(tiles), threading.Lock(), [], {}
    def worker():
        connection = http.client.HTTPConnection(url.hostname, url.port, timeout=60)
        while True:
            with lock:
                if not queue:
                    break
                z, x, y = queue.pop()
            start = time.perf_counter()
            connection.request("GET", f"/v1/jobs/{job}/tiles/{z}/{x}/{y}.png", headers=headers)
            response = connection.getresponse()
            response.read()
            with lock:
                latencies.append(time.perf_counter() - start)
                statuses[response.status] = statuses.get(response.status, 0) + 1
    start = time.perf_counter()
    threads = [threading.Thread(target=worker) for _ in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.perf_counter() - start
    latencies.sort()
    return (len(latencies) / wall, 1000 * statistics.median(latencies), 1000 * latencies[int(0.99 * (len(latencies) - 1))],
            statuses)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("base")
    parser.add_argument("job")
    parser.add_argument("--token")
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--pid", type=int)
    a = parser.parse_args()
    headers = {"Authorization": "Bearer " + a.token} if a.token else {}
    url = urllib.parse.urlsplit(a.base)
    connection = http.client.HTTPConnection(url.hostname, url.port, timeout=60)
    connection.request("GET", f"/v1/jobs/{a.job}/tiles.json", headers=headers)
    tilejson = json.loads(connection.getresponse().read())
    top = tilejson["maxzoom"]
    tiles = [t for z in range(max(0, top - 8), top + 1) for t in tile_range(*tilejson["bounds"], z)]
    random.Random(1).shuffle(tiles)
    for name in ("cold", "warm"):
        rate, p50, p99, statuses = run(a.base, a.job, headers, tiles, a.clients)
        print(f"{name}: {len(tiles)} tiles (zooms {max(0, top - 8)}-{top}), {a.clients} clients: {rate:.0f} tiles/s, "
              f"p50 {p50:.1f} ms, p99 {p99:.1f} ms, statuses {statuses}")
    if a.pid:
        status = open(f"/proc/{a.pid}/status").read()
        print("server", " ".join(line for line in status.splitlines() if line.startswith(("VmHWM", "VmRSS"))))


if __name__ == "__main__":
    main()

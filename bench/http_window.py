#!/usr/bin/env python3
"""How GDAL reads a job's map over the HTTP endpoint (docs/http.md): opens
/vsicurl/BASE/v1/jobs/JOB/map.tif, runs gdal.Info, then gdal.Translate of one window, and counts
the requests and bytes the server logged for each step (its `http GET ... 206 N bytes` lines).
Usage: /usr/bin/python3 bench/http_window.py http://HOST:PORT JOB SERVER_LOG X,Y,W,H
(a server with --dev-tenant, or GDAL_HTTP_HEADERS="Authorization: Bearer TOKEN" set)."""
from osgeo import gdal
gdal.UseExceptions()
base, job, log = sys.argv[1], sys.argv[2], sys.argv[3]
gdal.SetConfigOption("GDAL_DISABLE_READDIR_ON_OPEN", "EMPTY_DIR")
path = f"/v1/jobs/{job}/map.tif"
def served():
    lines = re.findall(r"http (GET|HEAD) " + re.escape(path) + r" (\d+) (\d+) bytes", open(log).read())
    return len(lines), sum(int(n) for m, s, n in lines if m == "GET")
r0 = served(); t = time.time()
ds = gdal.Open("/vsicurl/" + base + path)
info = gdal.Info(ds, format="json")
size = info["size"]; blocks = ds.GetRasterBand(1).GetBlockSize()
r1 = served(); t1 = time.time()
gdal.Translate("/vsimem/window.tif", ds, srcWin=[int(a) for a in sys.argv[4].split(",")])
r2 = served(); t2 = time.time()
print(f"map {size[0]}x{size[1]} blocks {blocks} bands {ds.RasterCount}")
print(f"open+info: {r1[0]-r0[0]} requests {r1[1]-r0[1]} bytes {t1-t:.2f} s")
print(f"{sys.argv[4]} window: {r2[0]-r1[0]} requests {r2[1]-r1[1]} bytes {t2-t1:.2f} s")

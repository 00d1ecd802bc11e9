#!/usr/bin/env bash
# GSF and BAG as a user meets them: inspect real GSF files, refuse a damaged one naming the
# record and byte, simulate a survey as GSF and process it as the bundle is processed, export
# the corrected pings, and read the BAG back with GDAL.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ex1811="$GSF_DATA/EX1811_EM302_0059_20181102_212138.gsf"
gsfpy="$GSF_DATA/gsfpy_test_data.gsf"

"$BATHYSLAM" inspect "$ex1811" > "$work/ex1811.txt"
grep -q "pings       50 (0 ignored), 432-432 beams per ping" "$work/ex1811.txt"
grep -q "time        2018-11-02T21:21:44.560Z .. 2018-11-02T21:26:43.068Z" "$work/ex1811.txt"
grep -q "latitude    17.83785 .. 17.84715" "$work/ex1811.txt"
grep -q "longitude   -64.59707 .. -64.59051" "$work/ex1811.txt"
grep -q "depth       1165.6 .. 2316.7 m" "$work/ex1811.txt"
grep -q "(EPSG:32620)" "$work/ex1811.txt"
"$BATHYSLAM" inspect "$gsfpy" | grep -q "pings       4 (0 ignored), 432-432 beams per ping"
# A ship's deep-water file maps at a cell its soundings fill (one per ~350 m² here): at a fixed
# 0.5 m no cell would hold the 3 soundings a cell needs, and there would be no map at all.
"$BATHYSLAM" process "$ex1811" --config odometry --out "$work/ex1811" > "$work/ex1811.out" 2>&1
grep -q "^map 64.00 m cells: map.tif" "$work/ex1811.out" || { cat "$work/ex1811.out"; exit 1; }
gdalinfo -stats "$work/ex1811/map.tif" > "$work/ex1811.gdal" 2>/dev/null
/usr/bin/python3 - "$work/ex1811.gdal" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
valid = float(re.search(r"STATISTICS_VALID_PERCENT=([0-9.]+)", text).group(1))
low, high = (float(re.search(rf"STATISTICS_{k}=(-?[0-9.]+)", text).group(1)) for k in ("MINIMUM", "MAXIMUM"))
assert valid > 25 and -2320 < low < high < -1165, (valid, low, high)
PY
"$BATHYSLAM" process "$ex1811" --config odometry --resolution 0.5 --out "$work/ex1811_fine" 2>&1 | grep -q "no map (no cell has enough soundings)"
"$BATHYSLAM" inspect --json --crs EPSG:32619 "$gsfpy" "$ex1811" > "$work/both.json"
/usr/bin/python3 - "$work/both.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert [f["pings"] for f in j["gsf_files"]] == [4, 50], j["gsf_files"]
assert j["survey"]["crs"] == "EPSG:32619", j["survey"]["crs"]
assert j["survey"]["counts"]["pings"] == 54, j["survey"]["counts"]
PY

# Damaged: cut inside the first ping (record 7 starts at byte 4000).
head -c 5000 "$gsfpy" > "$work/cut.gsf"
if "$BATHYSLAM" inspect "$work/cut.gsf" 2> "$work/cut.err"; then echo "a truncated file was accepted"; exit 1; fi
grep -q "cut.gsf: record 7 at byte 4000: truncated" "$work/cut.err"
# Given in the wrong time order.
if "$BATHYSLAM" inspect "$ex1811" "$gsfpy" 2> "$work/order.err"; then echo "files out of order accepted"; exit 1; fi
grep -q "give the files in time order" "$work/order.err"

# The same simulated survey as a bundle and as GSF gives the same dead-reckoning trajectory error.
"$BATHYSLAM" simulate --scenario small --seed 2 --out "$work/bundle" > /dev/null
"$BATHYSLAM" simulate --scenario small --seed 2 --format gsf --out "$work/gsf" > "$work/sim.txt"
grep -q "survey.gsf (4588 pings) and reference_nav.csv" "$work/sim.txt"
"$BATHYSLAM" process "$work/bundle" --config odometry --out "$work/pb" > /dev/null 2>&1
"$BATHYSLAM" process "$work/gsf/survey.gsf" --reference-nav "$work/gsf/reference_nav.csv" --config odometry \
  --export-gsf --export-soundings --out "$work/pg" > "$work/pg.txt" 2> /dev/null
grep -q "survey.corrected.gsf: 4588 of 4588 pings with the corrected navigation, all 4590 records kept" "$work/pg.txt"
grep -q "soundings.csv: 2349056 corrected soundings" "$work/pg.txt"
/usr/bin/python3 - "$work/pb/report.json" "$work/pg/report.json" <<'PY'
import json, sys
b, g = (json.load(open(p))["trajectory_error_m"]["optimized"]["rmse"] for p in sys.argv[1:])
assert abs(g - b) <= 0.01 * b, (b, g)
PY
"$BATHYSLAM" inspect "$work/pg/survey.corrected.gsf" | grep -q "soundings   2349056 of 2349056 beams"
# A bundle's pings exported as GSF.
"$BATHYSLAM" process "$work/bundle" --config odometry --export-gsf --out "$work/pbx" 2> /dev/null |
  grep -q "corrected.gsf: 4588 pings with the corrected navigation"
"$BATHYSLAM" inspect "$work/pbx/corrected.gsf" | grep -q "soundings   2349056 of 2349056 beams"
head -1 "$work/pg/soundings.csv" | grep -qx "easting,northing,elevation,line,submap"

# The BAG beside the GeoTIFF: same CRS, same grid, BAG's null value.
gdalinfo -json "$work/pg/map.bag" > "$work/bag.json"
gdalinfo -json "$work/pg/map.tif" > "$work/tif.json"
/usr/bin/python3 - "$work/bag.json" "$work/tif.json" <<'PY'
import json, sys
bag, tif = (json.load(open(p)) for p in sys.argv[1:])
assert bag["driverShortName"] == "BAG", bag["driverShortName"]
assert "UTM zone 51N" in bag["coordinateSystem"]["wkt"]
assert bag["size"] == tif["size"], (bag["size"], tif["size"])
assert all(abs(a - b) < 1e-6 for a, b in zip(bag["geoTransform"], tif["geoTransform"])), (bag["geoTransform"], tif["geoTransform"])
assert [b["description"] for b in bag["bands"]] == ["elevation", "uncertainty"], bag["bands"]
assert all(b["noDataValue"] == 1000000.0 for b in bag["bands"]), bag["bands"]
PY
# lake, the paper's survey, as a 236 MB GSF file: its BAG has the GeoTIFF's grid and values.
"$BATHYSLAM" simulate --scenario lake --seed 1 --format gsf --out "$work/lake" > /dev/null
rm -rf "$work/bundle" "$work/gsf" "$work/pb" "$work/pg" "$work/pbx"
"$BATHYSLAM" process "$work/lake/survey.gsf" --config odometry --out "$work/lo" > /dev/null 2>&1
gdalinfo -json "$work/lo/map.bag" > "$work/lbag.json"
gdalinfo -json "$work/lo/map.tif" > "$work/ltif.json"
/usr/bin/python3 - "$work/lbag.json" "$work/ltif.json" <<'PY'
import json, sys
bag, tif = (json.load(open(p)) for p in sys.argv[1:])
assert "UTM zone 51N" in bag["coordinateSystem"]["wkt"]
assert bag["size"] == tif["size"] and bag["size"][0] > 1500, (bag["size"], tif["size"])
assert all(abs(a - b) < 1e-6 for a, b in zip(bag["geoTransform"], tif["geoTransform"]))
PY
for xy in "0 0" "800 400" "300 200" "1200 600"; do
  # shellcheck disable=SC2086
  tif=$(gdallocationinfo -valonly "$work/lo/map.tif" $xy | head -2 | tr '\n' ' ')
  # shellcheck disable=SC2086
  bag=$(gdallocationinfo -valonly "$work/lo/map.bag" $xy | tr '\n' ' ')
  /usr/bin/python3 - "$tif" "$bag" <<'PY'
import math, sys
tif, bag = ([float(v) for v in a.split()] for a in sys.argv[1:])
assert len(tif) == 2 and len(bag) == 2, (tif, bag)
for t, b in zip(tif, bag):
    assert (math.isnan(t) and b == 1e6) or abs(t - b) < 1e-5, (tif, bag)
PY
done
echo "gsf cli: ok"

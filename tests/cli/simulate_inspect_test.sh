#!/usr/bin/env bash
# The CLI as a user runs it: simulate a survey, inspect it, and refuse a broken one clearly.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$BATHYSLAM" simulate --scenario small --seed 3 --drift dvl --out "$work/s" > "$work/sim.txt"
grep -q "simulated small (seed 3)" "$work/sim.txt"

"$BATHYSLAM" inspect "$work/s" > "$work/inspect.txt"
grep -qE "^lines       [67]$" "$work/inspect.txt"
/usr/bin/python3 - "$work/s" <<'PY'
import json, subprocess, sys, os
out = subprocess.run([os.environ["BATHYSLAM"], "inspect", "--json", sys.argv[1]],
                     check=True, capture_output=True, text=True).stdout
j = json.loads(out)
assert j["line_count"] in (6, 7), j["line_count"]
assert j["counts"]["soundings"] == 512 * j["counts"]["pings"], j["counts"]
assert j["drift"]["end_m"] > 0, j["drift"]
PY

# A .tar of the bundle folder reads as the folder does, in place; a tar that is not one bundle
# is refused with the reason.
tar -cf "$work/s.tar" -C "$work" s
"$BATHYSLAM" inspect "$work/s.tar" > "$work/inspect_tar.txt"
diff "$work/inspect.txt" "$work/inspect_tar.txt"
tar --format=pax -cf "$work/pax.tar" -C "$work" s
"$BATHYSLAM" inspect "$work/pax.tar" > "$work/inspect_pax.txt"
diff "$work/inspect.txt" "$work/inspect_pax.txt"
tar -cf "$work/nojson.tar" -C "$work" --exclude survey.json s
if "$BATHYSLAM" inspect "$work/nojson.tar" 2> "$work/err.txt"; then echo "inspect accepted a tar without survey.json" >&2; exit 1; fi
grep -q "nojson.tar: the tar holds no survey.json" "$work/err.txt"
echo "not a tar" > "$work/text.tar"
if "$BATHYSLAM" inspect "$work/text.tar" 2> "$work/err.txt"; then echo "inspect accepted a text file" >&2; exit 1; fi
grep -q "text.tar: neither a folder nor a tar" "$work/err.txt"
# Nothing in a tar is followed: a member that is a link has no bytes of its own in the tar
# (GDAL would offer the headers after it), so a bundle with one is refused naming it.
mkdir "$work/linked"
cp "$work/s/survey.json" "$work/s/nav.csv" "$work/linked/"
cp "$work/s/pings.csv" "$work/pings-elsewhere.csv"
ln -s ../pings-elsewhere.csv "$work/linked/pings.csv"
tar -cf "$work/symlink.tar" -C "$work" linked
if "$BATHYSLAM" inspect "$work/symlink.tar" 2> "$work/err.txt"; then echo "inspect followed a symbolic link" >&2; exit 1; fi
grep -q "symlink.tar: 'linked/pings.csv' is a symbolic link to '../pings-elsewhere.csv'" "$work/err.txt"
rm "$work/linked/pings.csv"
ln "$work/linked/nav.csv" "$work/linked/pings.csv"
tar -cf "$work/hardlink.tar" -C "$work" linked
if "$BATHYSLAM" inspect "$work/hardlink.tar" 2> "$work/err.txt"; then echo "inspect followed a hard link" >&2; exit 1; fi
grep -Eq "hardlink.tar: 'linked/(nav|pings).csv' is a hard link to 'linked/(nav|pings).csv'" "$work/err.txt"

# A bundle with a broken line: a non-zero exit and a message naming file, line and field.
sed -i '5s/^\([^,]*\),[^,]*,/\1,oops,/' "$work/s/nav.csv"
if "$BATHYSLAM" inspect "$work/s" 2> "$work/err.txt"; then
  echo "inspect accepted a broken bundle" >&2
  exit 1
fi
grep -q "nav.csv:5: easting: not a number: 'oops'" "$work/err.txt"
tar -cf "$work/broken.tar" -C "$work" s
if "$BATHYSLAM" inspect "$work/broken.tar" 2> "$work/err.txt"; then echo "inspect accepted a broken tar" >&2; exit 1; fi
grep -q "broken.tar/nav.csv:5: easting: not a number: 'oops'" "$work/err.txt"
echo "cli: simulate and inspect ok"

# Offline processing: odometry keeps dead reckoning, so its trajectory error is the DR error.
sed -i "5s/,oops,/,$(sed -n 5p "$work/s/reference_nav.csv" | cut -d, -f2),/" "$work/s/nav.csv"
"$BATHYSLAM" process "$work/s" --config odometry --out "$work/odo" > "$work/odo.txt" 2>/dev/null
/usr/bin/python3 - "$work/odo/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["trajectory_error_m"]
assert abs(t["optimized"]["rmse"] - t["dead_reckoning"]["rmse"]) < 1e-6, t
assert r["consistency_error_m"]["optimized"]["count"] > 1000, r["consistency_error_m"]
PY
test -s "$work/odo/trajectory.csv" && test -s "$work/odo/consistency_histogram.png"

# The fused map and its tiles: a COG per tile that gdalinfo reads, a .vdb beside it, a quicklook.
test -s "$work/odo/map.tif" && test -s "$work/odo/map.bag" && test -s "$work/odo/map.png"
grep -qE "^map 0.50 m cells: map.tif, map.bag, map.png, [0-9]+ tiles on [0-9]+ levels" "$work/odo.txt"
tile=$(ls "$work"/odo/tiles/0/*.tif | head -n 1)
test -s "${tile%.tif}.vdb"
gdalinfo "$tile" > "$work/gdalinfo.txt"
grep -q "LAYOUT=COG" "$work/gdalinfo.txt"
grep -q "COMPRESSION=ZSTD" "$work/gdalinfo.txt"
grep -q 'ID\["EPSG",32651\]' "$work/gdalinfo.txt"
test ! -e "$work/odo/map_difference.png"  # odometry has no dead reckoning to compare with
if "$BATHYSLAM" process "$work/s" --set registration.gicp.max_iterations=-3 --out "$work/bad" 2> "$work/err.txt"; then
  echo "process accepted an out-of-range parameter" >&2
  exit 1
fi
grep -q "parameter 'registration.gicp.max_iterations': -3 is outside" "$work/err.txt"
echo "cli: process ok"

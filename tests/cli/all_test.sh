#!/usr/bin/env bash
# Kongsberg EM .all as a user meets it: inspect the real files, process the deep-water one into a
# map that gdalinfo reads at the file's depths and a corrected GSF, and refuse a damaged file
# naming its byte offset and field.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
em2040="$ALL_DATA/0077_20221109_123655_Belgica.all"
em122="$ALL_DATA/0243_P007_MBES_EM122_20150207_044356_Supporter_GA4430.all"

"$BATHYSLAM" inspect "$em2040" > "$work/em2040.txt"
grep -q "Kongsberg EM2040 .all, 187693 bytes, 141 datagrams" "$work/em2040.txt"
grep -q "swaths      9 XYZ 88 from head(s) 2004, 2031, 4 outside the position fixes" "$work/em2040.txt"
grep -q "(EPSG:32631)" "$work/em2040.txt"
"$BATHYSLAM" inspect --json "$em122" > "$work/em122.json"
/usr/bin/python3 - "$work/em122.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
f = j["all_files"][0]
assert (f["swaths"], f["swaths_outside_navigation"], f["soundings"]) == (11, 2, 4749), f
assert 3470 < f["depth_m"][0] < f["depth_m"][1] < 3670, f["depth_m"]
assert j["survey"]["counts"]["pings"] == 9, j["survey"]["counts"]
PY
"$BATHYSLAM" process "$em122" --config mchs --export-gsf --out "$work/em122" > "$work/em122.out" 2>&1 ||
  { cat "$work/em122.out"; exit 1; }
grep -q "^corrected.gsf: 9 pings with the corrected navigation" "$work/em122.out"
"$BATHYSLAM" inspect "$work/em122/corrected.gsf" | grep -q "depth       3479.9 .. 3661.1 m"
gdalinfo -stats "$work/em122/map.tif" > "$work/em122.gdal" 2>/dev/null
/usr/bin/python3 - "$work/em122.gdal" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
low, high = (float(re.search(rf"STATISTICS_{k}=(-?[0-9.]+)", text).group(1)) for k in ("MINIMUM", "MAXIMUM"))
assert -3670 < low < high < -3470, (low, high)
PY
# A damaged file: one byte of the first XYZ 88 changed, the checksum no longer adds up.
cp "$em122" "$work/bad.all"
chmod u+w "$work/bad.all"
offset=$(/usr/bin/python3 - "$em122" <<'PY'
import struct, sys
b = open(sys.argv[1], "rb").read(); o = 0
while b[o + 5] != ord("X"): o += 4 + struct.unpack_from("<I", b, o)[0]
print(o)
PY
)
printf '\x7f' | dd of="$work/bad.all" bs=1 seek=$((offset + 100)) conv=notrunc status=none
if "$BATHYSLAM" process "$work/bad.all" --out "$work/bad" > "$work/bad.out" 2>&1; then
  echo "a damaged .all file was processed"; exit 1
fi
grep -q "bad.all:$offset: checksum: " "$work/bad.out" || { cat "$work/bad.out"; exit 1; }
echo "all_test: ok"

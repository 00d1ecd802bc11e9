#!/usr/bin/env bash
# XTF as a user meets it: inspect the real R2Sonic file and compare with a decoding written here
# from the format documents alone (Triton's XTF packets, R2Sonic's BTH0 sections), process it
# into a map that gdalinfo reads at the bay's depths and a corrected GSF, and refuse a damaged
# file naming its byte offset and field.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
xtf="$XTF_DATA/0009_150708_R2Testing_0001.xtf"

"$BATHYSLAM" inspect "$xtf" > "$work/inspect.txt"
grep -q "XTF from QINSy, R2Sonic 2026, 2163520 bytes, 3330 packets" "$work/inspect.txt"
grep -q "(EPSG:32610)" "$work/inspect.txt"
"$BATHYSLAM" inspect --json "$xtf" > "$work/inspect.json"
/usr/bin/python3 - "$xtf" "$work/inspect.json" > "$work/depths" <<'PY'
import calendar, collections, json, math, struct, sys
d = open(sys.argv[1], "rb").read()
assert d[0] == 123  # XTF file format
ox, oy, oz, oyaw, opitch, oroll = struct.unpack_from("<6f", d, 256 + 48)  # the bathymetry channel
counts = collections.Counter(); pings = beams = valid = 0
times, lats, lons, depths, roll = [], [], [], [], 0.0
pos = 1024
while pos < len(d):
    magic, kind, _, _, _, _, size = struct.unpack_from("<HBBHHHI", d, pos)
    assert magic == 0xFACE
    counts[str(kind)] += 1
    body = pos + 14
    if kind == 107:  # position: date, time, tenths of ms, then latitude and longitude
        lat, lon = struct.unpack_from("<2d", d, body + 9)
        lats.append(lat); lons.append(lon)
    elif kind == 3:  # attitude: roll at byte 20 of the body
        roll = struct.unpack_from("<f", d, body + 20)[0]
    elif kind == 65:  # 256-byte ping header, then R2Sonic's big-endian BTH0 packet
        q = body + 242
        assert d[q:q + 4] == b"BTH0"
        end = q + struct.unpack_from(">I", d, q + 4)[0]
        sections, k = {}, q + 12
        while k < end:
            name, n_bytes = struct.unpack_from(">2sH", d, k)
            sections[name] = k; k += n_bytes
        h0 = sections[b"H0"]
        seconds, nanos = struct.unpack_from(">II", d, h0 + 28)
        sound_speed = struct.unpack_from(">f", d, h0 + 44)[0]
        n = struct.unpack_from(">H", d, h0 + 114)[0]
        scale = struct.unpack_from(">f", d, sections[b"R0"] + 4)[0]
        ranges = [r * scale for r in struct.unpack_from(">%dH" % n, d, sections[b"R0"] + 8)]
        first, step = struct.unpack_from(">2f", d, sections[b"A2"] + 4)
        total, angles = 0, []
        for s in struct.unpack_from(">%dH" % n, d, sections[b"A2"] + 36):
            total += s; angles.append(first + total * step)
        words = struct.unpack_from(">%dI" % ((n + 7) // 8), d, sections[b"Q0"] + 4)
        flags = [(words[i // 8] >> (28 - 4 * (i % 8))) & 0xF for i in range(n)]
        pings += 1; beams += n; times.append(seconds + nanos * 1e-9)
        for r, a, f in zip(ranges, angles, flags):
            if r > 0 and f & 3 == 3 and f & 12:
                valid += 1
                depths.append(oz + sound_speed * r / 2 * math.cos(a - math.radians(roll + oroll)))
    pos += size
j = json.load(open(sys.argv[2]))
f = j["xtf_files"][0]
assert f["packets_by_type"] == dict(counts), (f["packets_by_type"], counts)
assert (f["pings"], f["beams"], f["soundings"], f["rejected_beams"]) == (pings, beams, valid, beams - valid), f
utc = lambda t: __import__("time").strftime("%Y-%m-%dT%H:%M:%SZ", __import__("time").gmtime(t))
assert (f["time_begin"], f["time_end"]) == (utc(min(times)), utc(max(times))), f
assert abs(f["latitude_deg"][0] - min(lats)) < 1e-9 and abs(f["latitude_deg"][1] - max(lats)) < 1e-9, f
assert abs(f["longitude_deg"][0] - min(lons)) < 1e-9 and abs(f["longitude_deg"][1] - max(lons)) < 1e-9, f
assert j["survey"]["counts"]["pings"] == pings, j["survey"]["counts"]
depths.sort()
print(depths[0], depths[len(depths) // 2], depths[-1])
PY
read -r low median high < "$work/depths"

"$BATHYSLAM" process "$xtf" --config odometry --out "$work/odometry" > "$work/odometry.out" 2>&1 ||
  { cat "$work/odometry.out"; exit 1; }
"$BATHYSLAM" process "$xtf" --config mchs --export-gsf --out "$work/mchs" > "$work/mchs.out" 2>&1 ||
  { cat "$work/mchs.out"; exit 1; }
grep -q "^corrected.gsf: 923 pings with the corrected navigation" "$work/mchs.out"
"$BATHYSLAM" inspect "$work/mchs/corrected.gsf" | grep -q "923 pings"
# The map's cells lie within the soundings' depths decoded above (within 0.1 m: the decoding
# leaves the sonar's mounting pitch and yaw out), their mean within 0.2 m of the soundings' median.
gdalinfo -stats "$work/mchs/map.tif" > "$work/map.gdal" 2>/dev/null
/usr/bin/python3 - "$work/map.gdal" "$low" "$median" "$high" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
low, median, high = map(float, sys.argv[2:])
stat = lambda k: float(re.search(rf"STATISTICS_{k}=(-?[0-9.]+)", text).group(1))
assert -high - 0.1 < stat("MINIMUM") < stat("MAXIMUM") < -low + 0.1, (stat("MINIMUM"), stat("MAXIMUM"), low, high)
assert abs(stat("MEAN") + median) < 0.2, (stat("MEAN"), median)
PY
# A damaged file: the first bathymetry packet's length cut to 100 bytes, less than its ping header.
cp "$xtf" "$work/bad.xtf"
chmod u+w "$work/bad.xtf"
printf '\x64\x00\x00\x00' | dd of="$work/bad.xtf" bs=1 seek=$((1152 + 10)) conv=notrunc status=none
if "$BATHYSLAM" process "$work/bad.xtf" --out "$work/bad" > "$work/bad.out" 2>&1; then
  echo "a damaged .xtf file was processed"; exit 1
fi
grep -q "bad.xtf:1152: R2Sonic bathymetry packet ping header up to SensorYcoordinate: runs past the end" "$work/bad.out" || { cat "$work/bad.out"; exit 1; }
echo "xtf_test: ok"

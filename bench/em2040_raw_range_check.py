#!/usr/bin/env python3
# Issue 36's EM2040 check, as far as it got: depths recomputed from the raw range and angle
# datagram (78, 'N') against the same pings' XYZ 88 depths, decoded here from Kongsberg's datagram
# description alone. Model: slant range = sound speed at the transducer x two-way time / 2 along a
# straight ray (the file's profile is 1497.9-1498.0 m/s throughout), the beam's angle from the
# vertical = its pointing angle re the receive array + the array's roll (installation S2R/S3R) +
# the vessel's roll at reception (+ the motion sensor's roll offset MSR), the transmit tilt as
# cos(tilt), and the receive array's height above the transmit transducer (S2Z/S3Z - S1Z).
#   /usr/bin/python3 bench/em2040_raw_range_check.py tests/data/all/0077_20221109_123655_Belgica.all
import bisect, math, struct, sys

data = open(sys.argv[1], "rb").read()
datagrams, at = [], 0
while at + 4 <= len(data):
    n = struct.unpack_from("<I", data, at)[0]
    _, date, ms, counter, serial = struct.unpack_from("<HIIHH", data, at + 6)
    datagrams.append((chr(data[at + 5]), at + 20, ms / 1000, counter, serial, at + 4 + n))
    at += 4 + n
inst = next(d for d in datagrams if d[0] == "I")
text = data[inst[1] + 4:inst[5] - 3].split(b"\0")[0].decode("latin1")
kv = dict(p.split("=", 1) for p in text.split(",") if "=" in p)
array_roll = {int(kv["R1S"]): float(kv["S2R"]), int(kv["R2S"]): float(kv["S3R"])}
array_height = {int(kv["R1S"]): float(kv["S2Z"]) - float(kv["S1Z"]), int(kv["R2S"]): float(kv["S3Z"]) - float(kv["S1Z"])}
roll_offset = float(kv["MSR"])
attitude = []
for kind, body, t0, *_ in datagrams:
    if kind == "A":
        for i in range(struct.unpack_from("<H", data, body)[0]):
            dt, _, roll = struct.unpack_from("<HHh", data, body + 2 + 12 * i)
            attitude.append((t0 + dt / 1000, roll / 100))
attitude.sort()
times = [a[0] for a in attitude]

def roll_at(t):
    i = min(max(bisect.bisect_left(times, t), 1), len(attitude) - 1)
    (ta, ra), (tb, rb) = attitude[i - 1], attitude[i]
    return ra + (t - ta) / (tb - ta) * (rb - ra)

xyz, raw = {}, {}
for kind, body, t, counter, serial, _ in datagrams:
    if kind == "X":
        beams = struct.unpack_from("<H", data, body + 8)[0]
        xyz[(counter, serial)] = [struct.unpack_from("<f", data, body + 20 + 20 * i)[0] for i in range(beams)]
    elif kind == "N":
        sound_speed, ntx, nrx = struct.unpack_from("<HHH", data, body)
        tilts = [struct.unpack_from("<h", data, body + 16 + 24 * i)[0] / 100 for i in range(ntx)]
        q = body + 16 + 24 * ntx
        beams = [struct.unpack_from("<hBBHBbf", data, q + 16 * i) for i in range(nrx)]
        raw[(counter, serial)] = (sound_speed / 10, tilts, beams, t)
errors = []
for key, (sound_speed, tilts, beams, t) in raw.items():
    if key not in xyz:
        continue
    for i, (angle, sector, detection, _, _, _, twtt) in enumerate(beams):
        if detection & 0x80 or i >= len(xyz[key]):
            continue
        level = math.radians(angle / 100 + array_roll[key[1]] + roll_at(t + twtt) + roll_offset)
        depth = sound_speed * twtt / 2 * math.cos(level) * math.cos(math.radians(tilts[sector])) + array_height[key[1]]
        errors.append((depth - xyz[key][i]) / xyz[key][i])
magnitudes = sorted(abs(e) for e in errors)
signed = sorted(errors)
print(f"{len(errors)} beams of {len(raw)} swaths: {sum(m < 0.01 for m in magnitudes) / len(magnitudes):.1%} within 1 % of "
      f"the XYZ 88 depth; |error| median {magnitudes[len(magnitudes) // 2]:.2%}, p95 {magnitudes[int(0.95 * len(magnitudes))]:.2%}; "
      f"signed median {signed[len(signed) // 2]:+.2%}")

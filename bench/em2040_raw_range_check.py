#!/usr/bin/env python3
# Issue 36's EM2040 check: depths recomputed from the raw range and angle datagram (78, 'N') against
# the same pings' XYZ 88 depths, decoded here from Kongsberg's datagram description alone.
#   /usr/bin/python3 bench/em2040_raw_range_check.py tests/data/all/0077_20221109_123655_Belgica.all [--require 95]
# --require P: exit 1 unless at least P % of beams lie within 1 % (the ctest em2040_raw_range).
# Model (vessel frame x forward, y starboard, z down; roll port up, pitch bow up, heading clockwise,
# all positive, turned as heading * pitch * roll):
# - The arrays: the transmit array is S1 (its axis the array's x), the receive array of head R1S is
#   S2, of head R2S is S3 (STC=3, one transmitter and two receivers; its axis the array's y, its face
#   the array's z), each turned by its installed roll, pitch and heading (S1H = 180.5: the
#   transmitter is mounted reversed, which the rotation carries).
# - The attitude: the motion sensor whose attitude datagrams say its roll and pitch were used in real
#   time (sensor system descriptor bits 1 and 2 clear), as logged (MB-System's
#   mbsys_simrad3_preprocess and Kluster's build_orientation_vectors add no MSR/MSP to it), at the
#   sector's transmit time (ping time + sector transmit delay) for the transmit array and at
#   reception (+ two-way travel time) for the receive array; held at the first sample before it.
# - The beam: the intersection of the transmit cone (angle to the transmit axis = 90 deg - tilt re
#   TX array, tilt positive forward) and the receive cone (angle to the receive axis = 90 deg +
#   pointing angle re RX array, positive to port) on the receive array's face side.
# - The range: the two-way travel time is the path transmitter -> seabed -> receiver, so along the
#   beam from the receive array rho + |rho b + d| = c t (d = receive array re transmit array),
#   straight rays at the transducer's sound speed (the file's profile is 1497.9-1498.0 m/s).
# - The depth: re the transmit transducer, as XYZ 88 gives it: d_z + rho b_z.
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
if kv.get("STC") != "3":
    sys.exit(f"{sys.argv[1]}: STC={kv.get('STC')}: only one transmitter with two receivers (STC=3) is modelled")
num = lambda *keys: [float(kv[k]) for k in keys]


def rotation(roll, pitch, heading):
    r, p, h = map(math.radians, (roll, pitch, heading))
    cr, sr, cp, sp, ch, sh = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(h), math.sin(h)
    return [[ch * cp, ch * sp * sr - sh * cr, ch * sp * cr + sh * sr],
            [sh * cp, sh * sp * sr + ch * cr, sh * sp * cr - ch * sr],
            [-sp, cp * sr, cp * cr]]


def apply(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


tx_position, tx_mount = num("S1X", "S1Y", "S1Z"), rotation(*num("S1R", "S1P", "S1H"))
rx_position = {int(kv["R1S"]): num("S2X", "S2Y", "S2Z"), int(kv["R2S"]): num("S3X", "S3Y", "S3Z")}
rx_mount = {int(kv["R1S"]): rotation(*num("S2R", "S2P", "S2H")), int(kv["R2S"]): rotation(*num("S3R", "S3P", "S3H"))}

attitude = []
for kind, body, t0, *_ in datagrams:
    if kind == "A":
        count = struct.unpack_from("<H", data, body)[0]
        if data[body + 2 + 12 * count] & 0x06:  # this sensor's roll or pitch was not the one in use
            continue
        for i in range(count):
            dt, _, roll, pitch, _, heading = struct.unpack_from("<HHhhhH", data, body + 2 + 12 * i)
            attitude.append((t0 + dt / 1000, roll / 100, pitch / 100, heading / 100))
attitude.sort()
times = [a[0] for a in attitude]


def attitude_at(t):
    i = bisect.bisect_left(times, t)
    if i == 0 or i == len(times):
        return attitude[min(i, len(times) - 1)][1:]
    (ta, *a), (tb, *b) = attitude[i - 1], attitude[i]
    f = (t - ta) / (tb - ta)
    b[2] = a[2] + (b[2] - a[2] + 180) % 360 - 180
    return [x + f * (y - x) for x, y in zip(a, b)]


def beam(tx_axis, rx_axis, rx_face, sin_tx, sin_rx):
    # the unit vector at sin_tx to the transmit axis and sin_rx to the receive axis, on the face side
    uu, vv, uv = dot(tx_axis, tx_axis), dot(rx_axis, rx_axis), dot(tx_axis, rx_axis)
    a = (sin_tx * vv - sin_rx * uv) / (uu * vv - uv * uv)
    b = (sin_rx * uu - sin_tx * uv) / (uu * vv - uv * uv)
    p = [a * x + b * y for x, y in zip(tx_axis, rx_axis)]
    w = cross(tx_axis, rx_axis)
    g = math.sqrt(max(0.0, 1 - dot(p, p)) / dot(w, w)) * (1 if dot(w, rx_face) > 0 else -1)
    return [x + g * y for x, y in zip(p, w)]


xyz, raw = {}, {}
for kind, body, t, counter, serial, _ in datagrams:
    if kind == "X":
        beams = struct.unpack_from("<H", data, body + 8)[0]
        xyz[(counter, serial)] = [struct.unpack_from("<f", data, body + 20 + 20 * i)[0] for i in range(beams)]
    elif kind == "N":
        sound_speed, ntx, nrx = struct.unpack_from("<HHH", data, body)
        sectors = [struct.unpack_from("<hHff", data, body + 16 + 24 * i) for i in range(ntx)]
        q = body + 16 + 24 * ntx
        beams = [struct.unpack_from("<hBBHBbf", data, q + 16 * i) for i in range(nrx)]
        raw[(counter, serial)] = (sound_speed / 10, sectors, beams, t)
errors, swaths = [], 0
for key, (sound_speed, sectors, beams, t) in raw.items():
    if key not in xyz:
        continue
    swaths += 1
    for i, (angle, sector, detection, _, _, _, twtt) in enumerate(beams):
        if detection & 0x80 or i >= len(xyz[key]):
            continue
        tilt, _, _, delay = sectors[sector]
        roll_t, pitch_t, heading_t = attitude_at(t + delay)
        roll_r, pitch_r, heading_r = attitude_at(t + delay + twtt)
        at_tx, at_rx = rotation(roll_t, pitch_t, 0), rotation(roll_r, pitch_r, heading_r - heading_t)
        rx = [apply(at_rx, apply(rx_mount[key[1]], axis)) for axis in ([0, 1, 0], [0, 0, 1])]
        b = beam(apply(at_tx, apply(tx_mount, [1, 0, 0])), rx[0], rx[1],
                 math.sin(math.radians(tilt / 100)), -math.sin(math.radians(angle / 100)))
        d = apply(at_tx, [r - s for r, s in zip(rx_position[key[1]], tx_position)])
        path = sound_speed * twtt
        rho = (path * path - dot(d, d)) / (2 * (path + dot(b, d)))
        depth = d[2] + rho * b[2]
        errors.append((depth - xyz[key][i]) / xyz[key][i])
magnitudes = sorted(abs(e) for e in errors)
signed = sorted(errors)
print(f"{len(errors)} beams of {swaths} swaths: {sum(m < 0.01 for m in magnitudes) / len(magnitudes):.1%} within 1 % of "
      f"the XYZ 88 depth; |error| median {magnitudes[len(magnitudes) // 2]:.2%}, p95 {magnitudes[int(0.95 * len(magnitudes))]:.2%}; "
      f"signed median {signed[len(signed) // 2]:+.2%}")
within = sum(m < 0.01 for m in magnitudes) / len(magnitudes)
if "--require" in sys.argv and within * 100 < float(sys.argv[sys.argv.index("--require") + 1]):
    sys.exit(f"{sys.argv[1]}: only {within:.1%} of beams within 1 % of the XYZ 88 depth")

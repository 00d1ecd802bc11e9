#!/usr/bin/env python3
"""How honest are the accepted loops' horizontal sigmas over a kept matrix? For every direction a
loop claims under 2 m: how many would be more than 2 m off if each covariance were exactly Gaussian
and honest, how many are, and the RMS and 3-sigma share of the errors in sigmas.

usage: /usr/bin/python3 bench/loop_error_tails.py TAG [WORK]   (Debian's python3-numpy)
WORK (default /tmp/mx2) holds the runs kept by `bench/robustness_matrix.sh --keep --tag TAG`."""
import glob
import json
import math
import sys

import numpy as np


def main():
    tag = sys.argv[1]
    work = sys.argv[2] if len(sys.argv) > 2 else "/tmp/mx2"
    expected, observed, sigmas_off = 0.0, 0, []
    for path in sorted(glob.glob(f"{work}/small-*-mchs-{tag}/report.json")):
        for g in json.load(open(path))["registrations"]:
            if g["type"] != "loop" or not g["accepted"] or g.get("exclusion") or "information" not in g:
                continue
            values, axes = np.linalg.eigh(np.array(g["information"]).reshape(6, 6)[:2, :2])
            error = np.array(g["error_sigmas"].get("error_at_anchor_m", [0.0, 0.0]))
            for k in range(2):
                if values[k] < 1 / 2.0**2:  # claims nothing within 2 m along this axis
                    continue
                sigma = 1 / math.sqrt(values[k])
                off = abs(error @ axes[:, k])
                expected += math.erfc(2 / sigma / math.sqrt(2))
                observed += off > 2
                sigmas_off.append(off / sigma)
    z = np.array(sigmas_off)
    print(f"{len(z)} loop directions claiming a sigma under 2 m; more than 2 m off: {expected:.1f} expected if honest, "
          f"{observed} observed; errors in sigmas: RMS {np.sqrt((z**2).mean()):.2f}, beyond 3 sigma "
          f"{100 * (z > 3).mean():.2f} % (Gaussian 0.27 %)")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""How much of a bundle's dead-reckoning error no relative constraint can remove.

Registrations and loop closures measure submaps against each other; a trajectory that is the
truth turned and scaled about its first pose agrees with every one of them. This prints the
horizontal DR error (RMSE against reference_nav.csv, first pose shared, as report.json's
trajectory error) and what is left after the best rotation, and rotation plus scale, about the
first pose: the part a relative-only method can hope to remove is the difference.

    /usr/bin/python3 bench/unobservable_drift.py BUNDLE [BUNDLE ...]     (needs python3-numpy)
"""
import sys

import numpy as np


def horizontal_track(path):
    nav = np.genfromtxt(path, delimiter=",", names=True)
    return (nav["easting"] - nav["easting"][0]) + 1j * (nav["northing"] - nav["northing"][0])


def rmse(z):
    return float(np.sqrt(np.mean(np.abs(z) ** 2)))


def main(bundles):
    print("| bundle | DR RMSE (m) | after best rotation (m) | after rotation and scale (m) | rotation (deg) | scale |")
    print("|---|---|---|---|---|---|")
    for bundle in bundles:
        dr, truth = horizontal_track(f"{bundle}/nav.csv"), horizontal_track(f"{bundle}/reference_nav.csv")
        n = min(len(dr), len(truth))
        dr, truth = dr[:n], truth[:n]
        # Least squares truth ≈ c·dr with complex c: |c| the scale, arg c the rotation.
        c = np.vdot(dr, truth) / np.vdot(dr, dr)
        turned = c / abs(c)
        print(f"| {bundle} | {rmse(dr - truth):.2f} | {rmse(turned * dr - truth):.2f} | {rmse(c * dr - truth):.2f} | "
              f"{np.degrees(np.angle(c)):.3f} | {abs(c):.4f} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])

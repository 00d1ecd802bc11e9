#!/usr/bin/python3
"""The `gicp` baseline's one uniform information, from the spread of its own registration errors.

Reads the report.json of a `gicp` run on a simulated survey (each registration carries its
error against the reference) and prints the `--set` arguments whose sigmas are robust estimates
of that spread: per horizontal axis median(horizontal error) / 1.1774 (the median of a
two-dimensional Gaussian's radius), depth and yaw median(|error|) / 0.6745. Roll and pitch are
taken from dead reckoning (keep_dr_roll_pitch) and left alone. Calibrate on a seed you do not
report.

    /usr/bin/python3 bench/calibrate_gicp_sigmas.py RUN/report.json
"""
import json
import math
import statistics
import sys


def main(path):
    registrations = [r for r in json.load(open(path))["registrations"] if r["accepted"]]
    if not registrations:
        sys.exit(f"{path}: no accepted registration to calibrate from")
    errors = [r["error_vs_reference"] for r in registrations]
    horizontal = statistics.median(e["horizontal_m"] for e in errors) / 1.1774
    depth = statistics.median(math.sqrt(max(e["translation_m"] ** 2 - e["horizontal_m"] ** 2, 0.0)) for e in errors) / 0.6745
    yaw = math.radians(statistics.median(abs(e["yaw_deg"]) for e in errors)) / 0.6745
    print(f"# from {len(errors)} registrations in {path}")
    print(f"--set gicp.sigma_x_m={horizontal:.3g} --set gicp.sigma_y_m={horizontal:.3g} "
          f"--set gicp.sigma_z_m={depth:.3g} --set gicp.sigma_yaw_rad={yaw:.3g}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])

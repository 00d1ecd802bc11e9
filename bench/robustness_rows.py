#!/usr/bin/env python3
"""One markdown row per configuration of one bundle, for bench/robustness_matrix.sh.

usage: robustness_rows.py TERRAIN DRIFT SEED CONFIG=REPORT.json...

The `check` column of an `mchs` row holds the issue's criteria, each failure named:
  worse-traj   trajectory RMSE more than 5 % above odometry's
  worse-cons   consistency RMSE above odometry's (1 mm tolerance for rounding)
  bad-loop     an accepted loop closure more than 2 m off the reference in position or 2 deg
               in turn, where its information claims that much (a sigma under 2 m or 2 deg)
  6sigma       an accepted edge off the reference by more than 6 sigma of its information (x, y
               and yaw jointly)
  3sigma       1 % or more of the accepted edges beyond 3 sigma
  below-gicp   consistency RMSE more than 5 % above `gicp`'s (issue 31)
"""
import json
import math
import sys


def claimed_error(registration):
    """A loop's error (m, deg) in what its information claims to know: its position along the
    horizontal directions whose sigma is under 2 m, its turn if its yaw sigma is under 2 deg. A
    depth-only edge (the direct path on flat ground) says nothing of where it lies, and its
    horizontal values are its guess's; an edge across a channel says nothing of where along it;
    a loop without yaw information says nothing of its turn."""
    info = registration.get("information_diagonal", [1, 1, 1, 1, 1, 1])
    e = registration["error_vs_reference"]
    sigmas = registration.get("error_sigmas", {})
    if "error_at_anchor_m" in sigmas and "information" in registration:
        full = registration["information"]
        xx, xy, yy = full[0], full[1], full[7]
        error = sigmas["error_at_anchor_m"]
        position2 = 0.0
        half_trace, root = (xx + yy) / 2, math.sqrt(((xx - yy) / 2) ** 2 + xy**2)
        for value in (half_trace + root, half_trace - root):  # eigenvalues of the x, y block
            if value < 1 / 2.0**2:
                continue
            # its eigenvector, and the error along it
            v = (xy, value - xx) if abs(xy) > 1e-12 else ((1.0, 0.0) if abs(value - xx) < abs(value - yy) else (0.0, 1.0))
            norm = math.hypot(*v)
            position2 += ((error[0] * v[0] + error[1] * v[1]) / norm) ** 2
        position = math.sqrt(position2)
    else:
        position = e["horizontal_m"] if max(info[0], info[1]) >= 1 / 2.0**2 else 0.0
    turn = abs(e["yaw_deg"]) if info[5] >= 1 / math.radians(2.0) ** 2 else 0.0
    return position, turn


def edge_sigmas(error_sigmas):
    """x, y and yaw together where the report has them (their cross terms count: Hessian-shaped
    information couples translation and yaw); otherwise the worse of the two blocks."""
    if "joint" in error_sigmas:
        return error_sigmas["joint"]
    return max(error_sigmas["horizontal"], error_sigmas["yaw"])


def summary(report):
    t = report["trajectory_error_m"]
    # null where no cell is seen by two lines (report.json says why): no figure, no check on it
    c = report["consistency_error_m"]["optimized"] or {"rmse": float("nan"), "p99": float("nan")}
    regs = report.get("registrations", [])
    accepted = [x for x in regs if x["accepted"]]
    loops = [x for x in accepted if x["type"] == "loop"]
    worst_loop = (0.0, 0.0)
    for x in loops:
        if x.get("error_vs_reference"):
            position, turn = claimed_error(x)
            worst_loop = (max(worst_loop[0], position), max(worst_loop[1], turn))
    sigmas = [edge_sigmas(x["error_sigmas"]) for x in accepted if "error_sigmas" in x]
    return {
        "traj": t["optimized"]["rmse"],
        "aligned": t.get("aligned", {}).get("optimized", {}).get("rmse", float("nan")),
        "cons": c["rmse"],
        "p99": c["p99"],
        "accepted": f"{len(accepted)}/{len(regs)}",
        "loops": len(loops),
        "worst_loop": worst_loop,
        "beyond3": sum(1 for s in sigmas if s > 3),
        "beyond6": sum(1 for s in sigmas if s > 6),
        "edges": len(sigmas),
        "net": report.get("safety_net", {}).get("verdict", "-"),
        "seconds": sum(report["timings_s"].values()),
    }


def checks(s, odometry, gicp=None):
    failed = []
    if s["traj"] > 1.05 * odometry["traj"]:
        failed.append("worse-traj")
    if math.isnan(s["cons"]):
        failed.append("no-cons")  # nothing to compare: not a pass
    if s["cons"] > odometry["cons"] + 0.001:
        failed.append("worse-cons")
    if s["worst_loop"][0] > 2.0 or s["worst_loop"][1] > 2.0:
        failed.append("bad-loop")
    if s["beyond6"] > 0:
        failed.append("6sigma")
    if s["edges"] and s["beyond3"] / s["edges"] >= 0.01:
        failed.append("3sigma")
    if gicp and s["cons"] > 1.05 * gicp["cons"]:
        failed.append("below-gicp")
    return " ".join(failed) if failed else "ok"


def main():
    terrain, drift, seed = sys.argv[1:4]
    runs = {}
    for arg in sys.argv[4:]:
        config, path = arg.split("=", 1)
        with open(path) as f:
            runs[config] = summary(json.load(f))
    odometry = runs.get("odometry")
    for config, s in runs.items():
        check = checks(s, odometry, runs.get("gicp")) if config == "mchs" and odometry else ""
        print(f"| {terrain} | {drift} | {seed} | {config} | {s['traj']:.2f} | {s['aligned']:.2f} | {s['cons']:.3f} | "
              f"{s['p99']:.3f} | {s['accepted']} | {s['loops']} | {s['worst_loop'][0]:.2f}, {s['worst_loop'][1]:.2f} | "
              f"{s['beyond3']} / {s['beyond6']} | {s['net']} | {s['seconds']:.0f} | {check} |")


if __name__ == "__main__":
    main()

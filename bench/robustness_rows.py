#!/usr/bin/env python3
"""One markdown row per configuration of one bundle, for bench/robustness_matrix.sh.

usage: robustness_rows.py TERRAIN DRIFT SEED CONFIG=REPORT.json...

The `check` column of an `mchs` row holds the issue's criteria, each failure named:
  worse-traj   trajectory RMSE more than 5 % above odometry's
  worse-cons   consistency RMSE above odometry's (1 mm tolerance for rounding)
  bad-loop     an accepted loop closure more than 2 m or 2 deg off the reference
  6sigma       an accepted edge off the reference by more than 6 sigma of its information
  3sigma       1 % or more of the accepted edges beyond 3 sigma
"""
import json
import sys


def summary(report):
    t = report["trajectory_error_m"]
    c = report["consistency_error_m"]["optimized"]
    regs = report.get("registrations", [])
    accepted = [x for x in regs if x["accepted"]]
    loops = [x for x in accepted if x["type"] == "loop"]
    worst_loop = (0.0, 0.0)
    for x in loops:
        e = x.get("error_vs_reference")
        if e:
            worst_loop = (max(worst_loop[0], e["horizontal_m"]), max(worst_loop[1], abs(e["yaw_deg"])))
    sigmas = [max(x["error_sigmas"]["horizontal"], x["error_sigmas"]["yaw"]) for x in accepted if "error_sigmas" in x]
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


def checks(s, odometry):
    failed = []
    if s["traj"] > 1.05 * odometry["traj"]:
        failed.append("worse-traj")
    if s["cons"] > odometry["cons"] + 0.001:
        failed.append("worse-cons")
    if s["worst_loop"][0] > 2.0 or s["worst_loop"][1] > 2.0:
        failed.append("bad-loop")
    if s["beyond6"] > 0:
        failed.append("6sigma")
    if s["edges"] and s["beyond3"] / s["edges"] >= 0.01:
        failed.append("3sigma")
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
        check = checks(s, odometry) if config == "mchs" and odometry else ""
        print(f"| {terrain} | {drift} | {seed} | {config} | {s['traj']:.2f} | {s['aligned']:.2f} | {s['cons']:.3f} | "
              f"{s['p99']:.3f} | {s['accepted']} | {s['loops']} | {s['worst_loop'][0]:.2f}, {s['worst_loop'][1]:.2f} | "
              f"{s['beyond3']} / {s['beyond6']} | {s['net']} | {s['seconds']:.0f} | {check} |")


if __name__ == "__main__":
    main()

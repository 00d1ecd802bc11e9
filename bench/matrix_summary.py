#!/usr/bin/env python3
"""Means per terrain and drift of a robustness matrix (bench/robustness_matrix.sh's rows), with
issue 31's checks over them.

usage: matrix_summary.py ROWS.md

Per (terrain, drift): the mean over seeds of trajectory RMSE, aligned RMSE, consistency RMSE and
p99 for each configuration in the rows (odometry, gicp, mchs, floor, identifiable). Then:
  runs ok            mchs rows whose `check` column is ok (robustness_rows.py's checks)
  floor share        where the observable floor lowers the trajectory or the consistency RMSE
                     by more than 10 % below odometry (mean over seeds), the share of that
                     reduction mchs achieves (issue 31 asks for at least 70 %); the same
                     against the identifiable floor (bench_oracle_graph --identifiable: what
                     pair-by-pair decisions can reach where aliases are) when its rows are there
"""
import collections
import sys


def rows(path):
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 15 or cells[0] in ("terrain", "variant", "---") or cells[0].startswith("-"):
            continue
        yield cells


FLOORS = ("floor", "identifiable")


def share_cell(mean, floor_name, k, terrain, drift, shares):
    """The share of the floor's reduction below odometry that mchs achieves in figure k, where the
    floor gains more than 10 %; '-' elsewhere."""
    if floor_name not in mean or "odometry" not in mean or "mchs" not in mean:
        return "-"
    odometry, floor, mchs = mean["odometry"][k], mean[floor_name][k], mean["mchs"][k]
    if not floor < 0.9 * odometry:
        return "-"
    share = (odometry - mchs) / (odometry - floor)
    shares.append((share, terrain, drift, "traj" if k == 0 else "cons"))
    return f"{share:.2f}"


def main():
    groups = collections.OrderedDict()
    checks = collections.Counter()
    failures = []
    for c in rows(sys.argv[1]):
        terrain, drift, seed, config = c[0], c[1], c[2], c[3]
        figures = [float(c[k]) for k in (4, 5, 6, 7)]
        groups.setdefault((terrain, drift), collections.defaultdict(list))[config].append(figures)
        if config == "mchs":
            checks[c[14] == "ok"] += 1
            if c[14] != "ok":
                failures.append(f"{terrain} {drift} {seed}: {c[14]}")
    floors = [f for f in FLOORS if any(f in by_config for by_config in groups.values())]
    print("| terrain | drift | trajectory RMSE (m) | aligned (m) | consistency RMSE (m) | p99 (m) | "
          + " | ".join(f"{f} share traj / cons" for f in floors) + " |")
    print("|---|---|---|---|---|---|" + "---|" * len(floors))
    shares = {f: [] for f in floors}
    for (terrain, drift), by_config in groups.items():
        names = [n for n in ("odometry", "gicp", "mchs") + FLOORS if n in by_config]
        mean = {n: [sum(v[k] for v in by_config[n]) / len(by_config[n]) for k in range(4)] for n in names}
        cells = [" / ".join(f"{mean[n][k]:.{2 if k < 2 else 3}f}" for n in names) for k in range(4)]
        for f in floors:
            cells.append(" / ".join(share_cell(mean, f, k, terrain, drift, shares[f]) for k in (0, 2)))
        print(f"| {terrain} | {drift} | " + " | ".join(cells) + " |")
    print()
    print(f"configurations per cell: {' / '.join(('odometry', 'gicp', 'mchs') + FLOORS)} (those present)")
    print(f"mchs runs ok: {checks[True]} of {checks[True] + checks[False]}")
    for f in failures:
        print(f"  {f}")
    for f in floors:
        met = sum(1 for s in shares[f] if s[0] >= 0.7)
        print(f"{f} share >= 0.70: {met} of {len(shares[f])} terrain x drift x metric where the {f} gains > 10 %")
        for s in sorted(shares[f])[:12]:
            if s[0] < 0.7:
                print(f"  {s[1]} {s[2]} {s[3]}: {s[0]:.2f}")


if __name__ == "__main__":
    main()

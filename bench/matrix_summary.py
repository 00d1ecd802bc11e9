#!/usr/bin/env python3
"""Means per terrain and drift of a robustness matrix (bench/robustness_matrix.sh's rows), with
issue 31's checks over them.

usage: matrix_summary.py ROWS.md

Per (terrain, drift): the mean over seeds of trajectory RMSE, aligned RMSE, consistency RMSE and
p99 for each configuration in the rows (odometry, gicp, mchs, floor). Then:
  runs ok            mchs rows whose `check` column is ok (robustness_rows.py's checks)
  floor share        where the observable floor lowers the trajectory or the consistency RMSE
                     by more than 10 % below odometry (mean over seeds), the share of that
                     reduction mchs achieves (issue 31 asks for at least 70 %)
"""
import collections
import sys


def rows(path):
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 15 or cells[0] in ("terrain", "---") or cells[0].startswith("-"):
            continue
        yield cells


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
    print("| terrain | drift | trajectory RMSE (m) | aligned (m) | consistency RMSE (m) | p99 (m) | floor share traj / cons |")
    print("|---|---|---|---|---|---|---|")
    shares = []
    for (terrain, drift), by_config in groups.items():
        names = [n for n in ("odometry", "gicp", "mchs", "floor") if n in by_config]
        mean = {n: [sum(v[k] for v in by_config[n]) / len(by_config[n]) for k in range(4)] for n in names}
        cells = [" / ".join(f"{mean[n][k]:.{2 if k < 2 else 3}f}" for n in names) for k in range(4)]
        share_cells = []
        for k in (0, 2):
            if "floor" not in mean or "odometry" not in mean or "mchs" not in mean:
                share_cells.append("-")
                continue
            odometry, floor, mchs = mean["odometry"][k], mean["floor"][k], mean["mchs"][k]
            if floor < 0.9 * odometry:
                share = (odometry - mchs) / (odometry - floor)
                shares.append((share, terrain, drift, "traj" if k == 0 else "cons"))
                share_cells.append(f"{share:.2f}")
            else:
                share_cells.append("-")
        print(f"| {terrain} | {drift} | " + " | ".join(cells) + f" | {' / '.join(share_cells)} |")
    print()
    print(f"configurations per cell: {' / '.join(n for n in ('odometry', 'gicp', 'mchs', 'floor'))} (those present)")
    print(f"mchs runs ok: {checks[True]} of {checks[True] + checks[False]}")
    for f in failures:
        print(f"  {f}")
    met = sum(1 for s in shares if s[0] >= 0.7)
    print(f"floor share >= 0.70: {met} of {len(shares)} terrain x drift x metric where the floor gains > 10 %")
    for s in sorted(shares)[:12]:
        if s[0] < 0.7:
            print(f"  {s[1]} {s[2]} {s[3]}: {s[0]:.2f}")


if __name__ == "__main__":
    main()

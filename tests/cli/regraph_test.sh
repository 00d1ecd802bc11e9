#!/usr/bin/env bash
# report.json keeps each registration's measured pose, anchor and information: re-solving the
# graph from them (bench_regraph) gives the run's own trajectory and consistency, and other
# weights give other answers.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$BATHYSLAM" simulate --scenario small --seed 2 --drift paper --out "$work/s" > /dev/null
"$BATHYSLAM" process "$work/s" --config gicp --out "$work/gicp" > /dev/null 2>&1
"$REGRAPH" "$work/s" "$work/gicp/report.json" > "$work/same.txt"
"$REGRAPH" "$work/s" "$work/gicp/report.json" --uniform uniform_information.sigma_translation_m.x=0.05 uniform_information.sigma_translation_m.y=0.05 > "$work/tight.txt"
/usr/bin/python3 - "$work/gicp/report.json" "$work/same.txt" "$work/tight.txt" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
def rmse(path):
    m = re.search(r"trajectory RMSE ([0-9.]+) m .*consistency RMSE ([0-9.]+) m", open(path).read())
    return float(m.group(1)), float(m.group(2))
run = (r["trajectory_error_m"]["optimized"]["rmse"], r["consistency_error_m"]["optimized"]["rmse"])
same, tight = rmse(sys.argv[2]), rmse(sys.argv[3])
assert abs(same[0] - run[0]) < 0.006 and abs(same[1] - run[1]) < 0.0006, (same, run)
assert abs(tight[0] - run[0]) > 0.01, (tight, run)
assert all(len(g["information_diagonal"]) == 6 for g in r["registrations"] if g["accepted"])
PY
if "$REGRAPH" "$work/s" "$work/missing.json" 2> "$work/err.txt"; then
  echo "bench_regraph accepted a missing report" >&2
  exit 1
fi
grep -q "missing.json: cannot be read" "$work/err.txt"
echo "regraph ok"

#!/usr/bin/env bash
# The configuration tables of docs/results/ (slam-results.md, robustness.md): simulates a
# scenario for several seeds, processes each bundle with each configuration, and prints one
# markdown row per (seed, configuration).
#   bench/scenario_table.sh [--scenario lake] [--drift paper] [--seeds "1 2 3 4 5"]
#                           [--configs "odometry gicp"] [--work DIR]
#                           [--set "key=value ..."] [--tag NAME]
# Bundles and outputs go under DIR (default /tmp/bathyslam-bench) and are reused when present;
# --set passes parameters to every run, --tag names their output directories apart.
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=lake drift=paper seeds="1 2 3 4 5" configs="odometry gicp" work=/tmp/bathyslam-bench sets="" tag=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenario) scenario=$2; shift 2 ;;
    --drift) drift=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --configs) configs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --set) sets=$2; shift 2 ;;
    --tag) tag=-$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
bathyslam=${BATHYSLAM:-build/client/bathyslam}
mkdir -p "$work"
echo "| seed | config | trajectory RMSE (m) | mean (m) | std (m) | consistency RMSE (m) | p95 (m) | p99 (m) | registrations accepted | time (s) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for seed in $seeds; do
  bundle=$work/$scenario-$drift-$seed
  [[ -f $bundle/survey.json ]] || "$bathyslam" simulate --scenario "$scenario" --drift "$drift" --seed "$seed" --out "$bundle" >/dev/null
  for config in $configs; do
    out=$bundle-$config$tag
    set_args=()
    for kv in $sets; do set_args+=(--set "$kv"); done
    "$bathyslam" process "$bundle" --config "$config" --out "$out" "${set_args[@]}" >/dev/null
    python3 - "$out/report.json" "$seed" "$config" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
t = r["trajectory_error_m"]["optimized"]
c = r["consistency_error_m"]["optimized"]
regs = r.get("registrations", [])
accepted = sum(1 for x in regs if x["accepted"])
seconds = sum(r["timings_s"].values())
print(f"| {sys.argv[2]} | {sys.argv[3]} | {t['rmse']:.2f} | {t['mean']:.2f} | {t['std']:.2f} | "
      f"{c['rmse']:.3f} | {c['p95']:.3f} | {c['p99']:.3f} | {accepted}/{len(regs)} | {seconds:.0f} |")
PY
  done
done

#!/usr/bin/env bash
# Seabeds and sonars the robustness matrix does not make (issue 31: "checked on seabeds you have
# never seen"): sand waves 3 m and 80 m long, crests along and across the lines, lines 15 and 55 m
# apart, 30 and 40 m altitude, a 90-degree 128-beam sonar whose adjacent lines do not overlap, 64
# and 1,024 beams; every drift model; `small` size. One markdown row per (variant, drift, seed,
# configuration) with the matrix's checks (bench/robustness_rows.py).
#   bench/unseen_seabeds.sh [--seeds "1 2"] [--configs "odometry gicp mchs"] [--work DIR]
#                           [--set "key=value ..."] [--tag NAME] [--keep]
# Bundles go under DIR (default /tmp/bathyslam-unseen) and are reused when present.
set -euo pipefail
cd "$(dirname "$0")/.."
seeds="1 2" configs="odometry gicp mchs" work=/tmp/bathyslam-unseen sets="" tag="" keep=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seeds) seeds=$2; shift 2 ;;
    --configs) configs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --set) sets=$2; shift 2 ;;
    --tag) tag=-$2; shift 2 ;;
    --keep) keep=1; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
bathyslam=${BATHYSLAM:-build/client/bathyslam}
mkdir -p "$work"
set_args=()
for kv in $sets; do set_args+=(--set "$kv"); done
variants=(
  "sw3|--terrain sandwaves --wavelength 3"
  "sw80|--terrain sandwaves --wavelength 80"
  "swa0|--terrain sandwaves --wave-angle 0"
  "swa90|--terrain sandwaves --wave-angle 90"
  "mixls15|--terrain mixed --line-spacing 15"
  "mixls55|--terrain mixed --line-spacing 55"
  "mixalt30|--terrain mixed --altitude 30"
  "chb128|--terrain channel --beams 128 --swath 90"
  "lakeb64|--terrain lake --beams 64"
  "boulalt40|--terrain boulders --altitude 40"
  "slopels45|--terrain slopebreak --line-spacing 45"
  "flatb1024|--terrain flat --beams 1024 --swath 120"
)
echo "| variant | drift | seed | config | trajectory RMSE (m) | aligned RMSE (m) | consistency RMSE (m) | p99 (m) | accepted | loops | worst loop (m, deg) | beyond 3σ / 6σ | safety net | time (s) | check |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for variant in "${variants[@]}"; do
  name=${variant%%|*}
  read -ra simulate_args <<< "${variant#*|}"
  for drift in paper dvl heading-walk compass-step; do
    for seed in $seeds; do
      bundle=$work/$name-$drift-$seed
      [[ -f $bundle/survey.json ]] ||
        "$bathyslam" simulate --scenario small "${simulate_args[@]}" --drift "$drift" --seed "$seed" --out "$bundle" >/dev/null
      reports=()
      for config in $configs; do
        out=$bundle-$config$tag
        "$bathyslam" process "$bundle" --config "$config" --out "$out" "${set_args[@]}" > "$out.log" 2>&1 ||
          { echo "failed: $config on $bundle; see $out.log" >&2; exit 1; }
        reports+=("$config=$out/report.json")
      done
      python3 bench/robustness_rows.py "$name" "$drift" "$seed" "${reports[@]}"
      [[ $keep == 1 ]] || rm -rf "$bundle"
    done
  done
done

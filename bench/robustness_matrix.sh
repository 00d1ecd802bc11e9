#!/usr/bin/env bash
# The robustness matrix (issue 14): every terrain kind x every drift model x seeds, each bundle
# processed by every configuration; one markdown row per (terrain, drift, seed, configuration)
# and, per `mchs` run, the checks the issue sets: never worse than odometry, no accepted loop
# closure off by more than 2 m or 2 deg, no edge confidently wrong (beyond 6 sigma; fewer than
# 1 % beyond 3 sigma).
#   bench/robustness_matrix.sh [--scenario small] [--terrains "..."] [--drifts "..."]
#                              [--seeds "1 2 3"] [--configs "odometry gicp mchs"] [--work DIR]
#                              [--set "key=value ..."] [--tag NAME] [--floor] [--altitude M]
#                              [--simulate "ARGS"] [--label NAME]
# --floor adds a `floor` row per bundle: the observable floor (bench_oracle_graph --observable),
# every candidate pair at the truth with the information its overlap supports, and an
# `identifiable` row: the same where dead reckoning rules out every alias of the truth
# (bench_oracle_graph --identifiable). --altitude flies
# the sonar that high, the world scaled with it (simulate --altitude; issue 38). --simulate adds
# arguments to every simulate (a seabed or sonar the defaults do not make), and --label names the
# rows and bundles in place of the terrain (bench/unseen_seabeds.sh).
# bench/matrix_summary.py turns the rows into means per terrain and drift with issue 31's checks.
# Bundles go under DIR (default /tmp/bathyslam-robust) and are reused when present; each bundle
# is deleted after its runs unless --keep is given (a `small` bundle is ~60 MB).
set -euo pipefail
cd "$(dirname "$0")/.."
scenario=small seeds="1 2 3" configs="odometry gicp mchs" work=/tmp/bathyslam-robust sets="" tag="" keep=0 floor=0
altitude_args=() altitude_tag="" simulate_args=() label=""
terrains="lake sandwaves boulders channel slopebreak flat mixed"
drifts="paper dvl heading-walk compass-step"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenario) scenario=$2; shift 2 ;;
    --terrains) terrains=$2; shift 2 ;;
    --drifts) drifts=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --configs) configs=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --set) sets=$2; shift 2 ;;
    --tag) tag=-$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --floor) floor=1; shift ;;
    --altitude) altitude_args=(--altitude "$2"); altitude_tag=-altitude$2; shift 2 ;;
    --simulate) read -ra simulate_args <<< "$2"; shift 2 ;;
    --label) label=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
bathyslam=${BATHYSLAM:-build/client/bathyslam}
oracle=${BENCH_ORACLE:-build/bench/bench_oracle_graph}
mkdir -p "$work"
set_args=()
for kv in $sets; do set_args+=(--set "$kv"); done

echo "| terrain | drift | seed | config | trajectory RMSE (m) | aligned RMSE (m) | consistency RMSE (m) | p99 (m) | accepted | loops | worst loop (m, deg) | beyond 3σ / 6σ | safety net | time (s) | check |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for terrain in $terrains; do
  for drift in $drifts; do
    for seed in $seeds; do
      row=${label:-$terrain}
      bundle=$work/$scenario$altitude_tag-$row-$drift-$seed
      [[ -f $bundle/survey.json ]] ||
        "$bathyslam" simulate --scenario "$scenario" --terrain "$terrain" --drift "$drift" --seed "$seed" \
          "${altitude_args[@]}" "${simulate_args[@]}" --out "$bundle" >/dev/null
      reports=()
      for config in $configs; do
        out=$bundle-$config$tag
        "$bathyslam" process "$bundle" --config "$config" --out "$out" "${set_args[@]}" >/dev/null
        reports+=("$config=$out/report.json")
      done
      if [[ $floor == 1 ]]; then
        # The floors' figures in a report's shape, for robustness_rows.py.
        for mode in observable identifiable; do
          name=floor; [[ $mode == identifiable ]] && name=identifiable
          "$oracle" "$bundle" --$mode | awk '$1 == "floor" {printf "{\"trajectory_error_m\": {\"optimized\": {\"rmse\": %s}, \"aligned\": {\"optimized\": {\"rmse\": %s}}}, \"consistency_error_m\": {\"optimized\": {\"rmse\": %s, \"p99\": %s}}, \"timings_s\": {}}\n", $2, $3, $4, $5}' \
            > "$bundle-$name.json"
          reports+=("$name=$bundle-$name.json")
        done
      fi
      python3 bench/robustness_rows.py "$row" "$drift" "$seed" "${reports[@]}"
      [[ $keep == 1 ]] || rm -rf "$bundle"
    done
  done
done

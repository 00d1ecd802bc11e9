#!/usr/bin/env bash
# Seabeds and sonars the robustness matrix does not make (issue 31: "checked on seabeds you have
# never seen"): sand waves 3 m and 80 m long, crests along and across the lines, lines 15 and 55 m
# apart, 30 and 40 m altitude, a 90-degree 128-beam sonar whose adjacent lines do not overlap, 64
# and 1,024 beams; every drift model; `small` size. The matrix's rows and checks
# (bench/robustness_matrix.sh with --simulate and --label), the variant's name for the terrain.
#   bench/unseen_seabeds.sh [--seeds "1 2"] [--configs "odometry gicp mchs"] [--work DIR]
#                           [--set "key=value ..."] [--tag NAME] [--keep]
# Every option goes to robustness_matrix.sh; bundles go under DIR (default /tmp/bathyslam-unseen).
set -euo pipefail
cd "$(dirname "$0")/.."
variants=(  # name | terrain | more simulate arguments
  "sw3|sandwaves|--wavelength 3"
  "sw80|sandwaves|--wavelength 80"
  "swa0|sandwaves|--wave-angle 0"
  "swa90|sandwaves|--wave-angle 90"
  "mixls15|mixed|--line-spacing 15"
  "mixls55|mixed|--line-spacing 55"
  "mixalt30|mixed|--altitude 30"
  "chb128|channel|--beams 128 --swath 90"
  "lakeb64|lake|--beams 64"
  "boulalt40|boulders|--altitude 40"
  "slopels45|slopebreak|--line-spacing 45"
  "flatb1024|flat|--beams 1024 --swath 120"
)
header=1
for variant in "${variants[@]}"; do
  IFS='|' read -r name terrain simulate <<< "$variant"
  bench/robustness_matrix.sh --seeds "1 2" --work /tmp/bathyslam-unseen "$@" \
    --terrains "$terrain" --simulate "$simulate" --label "$name" | tail -n +$((header == 1 ? 1 : 3))
  header=0
done

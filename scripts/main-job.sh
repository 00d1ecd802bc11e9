#!/usr/bin/env bash
# The README's main-job command. For now (foundation issue): build, simulate the `small`
# survey and print its summary. Later issues extend it to the full service round trip.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=${BATHYSLAM_DEMO_DIR:-demo}
mkdir -p "$out"
./build/client/bathyslam simulate --scenario small --seed 1 --drift paper --out "$out/small"
./build/client/bathyslam inspect "$out/small"
./build/client/bathyslam inspect --json "$out/small" > "$out/small-summary.json"
echo
echo "bundle:  $out/small"
echo "summary: $out/small-summary.json"

#!/usr/bin/env bash
# `mchs` as a user runs it on two `small` surveys, judged by the robustness matrix's checks
# (bench/robustness_rows.py): on the lake terrain it must help and close loops correctly; on
# sand waves, where every feature match has an alias a wavelength away, it must not be worse
# than dead reckoning and must close no wrong loop.
set -euo pipefail
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows="$(dirname "$0")/../../bench/robustness_rows.py"

# The paper's method: every defence of issue 14 off, and every addition of issue 31.
literal=(--set quality.doubt_widens=0 --set robustness.dr_gate=0 --set robustness.consistency=0 --set robustness.safety_net=0 --set acceptance.min_distinctness=0
         --set acceptance.max_competitor_ratio=0 --set quality.direct_depth_from_relief=0 --set quality.best_sigma_rotation_rad.yaw=0.004
         --set quality.information_from_hessian=0 --set quality.start_check_share=0 --set quality.max_nearby_improvement=0
         --set direct_loops.enabled=0 --set navigation_noise.estimate=0 --set robustness.alias_from_prior=0
         --set robustness.publish_rule=0)

check() {  # terrain drift seed [simulate options] [-- process options] -> the mchs row's check column
  local bundle="$work/$1-$2-$3" terrain=$1 drift=$2 seed=$3
  shift 3
  local sim=() proc=()
  while [[ $# -gt 0 && $1 != -- ]]; do sim+=("$1"); shift; done
  [[ $# -gt 0 ]] && shift && proc=("$@")
  [[ -f $bundle/survey.json ]] ||
    "$BATHYSLAM" simulate --scenario small --terrain "$terrain" --drift "$drift" --seed "$seed" "${sim[@]}" --out "$bundle" > /dev/null
  [[ -f $bundle-odometry/report.json ]] || "$BATHYSLAM" process "$bundle" --config odometry --out "$bundle-odometry" > /dev/null 2>&1
  rm -rf "$bundle-mchs"
  "$BATHYSLAM" process "$bundle" --config mchs --out "$bundle-mchs" --threads 2 "${proc[@]}" > /dev/null 2>&1
  set -- "$terrain" "$drift" "$seed"

  python3 "$rows" "$1" "$2" "$3" "odometry=$bundle-odometry/report.json" "mchs=$bundle-mchs/report.json" |
    tee -a "$work/rows" | awk -F'|' '$5 ~ /mchs/ {gsub(/ /, "", $16); print $16}'
}

verdict=$(check lake paper 2)
[ "$verdict" = ok ] || { cat "$work/rows"; echo "lake: $verdict" >&2; exit 1; }
# It must also have corrected the drift and closed loops there, or the check proves nothing.
awk -F'|' '$5 ~ /odometry/ {o = $6} $5 ~ /mchs/ {m = $6; l = $11} END {exit !(m < 0.5 * o && l > 0)}' "$work/rows" ||
  { cat "$work/rows"; echo "lake: mchs did not correct the drift with loop closures" >&2; exit 1; }

# Sand waves 12 m apart and a compass step: the paper's method closes a loop a wavelength off
# and ends worse than dead reckoning; the defences must not.
verdict=$(check sandwaves compass-step 3 --wavelength 12 -- "${literal[@]}")
[[ $verdict == *bad-loop* && $verdict == *worse-traj* ]] ||
  { cat "$work/rows"; echo "sand waves: the paper's method passed ($verdict): the survey does not stress mchs" >&2; exit 1; }
verdict=$(check sandwaves compass-step 3 --wavelength 12)
[ "$verdict" = ok ] || { cat "$work/rows"; echo "sand waves: $verdict" >&2; exit 1; }
echo "robustness checks passed"

#!/usr/bin/env bash
# Fair sharing under hostile load (issue 37): a private cluster and a server with no job workers
# (so tenant A's job stays queued and its WatchJob streams stay open), three tenants with tokens,
# then bench/fairness.py: A's 2,000 streams, B's 24 concurrent finalizes, C's ListSurveys latency.
#   bash bench/fairness.sh BUNDLE [BUILD_DIR=build] [fairness.py options: --streams --finalizers --seconds]
# BUNDLE: a survey bundle folder (e.g. `bathyslam simulate --scenario small --out DIR`).
# SERVER_ARGS in the environment: more server options (e.g. "--max-threads 256").
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bundle=$(realpath "$1")
build=$(realpath "${2:-$root/build}")
shift $(( $# < 2 ? $# : 2 ))
source "$root/bench/private_server.sh"
server="$build/server/bathyslam-server"
token() { "$server" token create --db "$url" --tenant "$1"; }
token_a=$(token a) token_b=$(token b) token_c=$(token c)
# shellcheck disable=SC2086  # SERVER_ARGS: options, split on purpose
start_private_server --workers 0 ${SERVER_ARGS:-}

survey=$(BATHYSLAM_TOKEN=$token_a "$build/client/bathyslam" upload "$bundle" 2> /dev/null | awk '/^survey .* ready$/ {print $2}')
job=$(BATHYSLAM_TOKEN=$token_a "$build/client/bathyslam" submit "$survey" --config odometry | awk '/^job/ {print $2}')
echo "server $BATHYSLAM_SERVER (pid $server_pid, no workers), tenant A's job $job queued; $(nproc) cores"
PYTHONPATH="$build/python" /usr/bin/python3 "$root/bench/fairness.py" "$BATHYSLAM_SERVER" "$server_pid" "$bundle" \
  "$token_a" "$token_b" "$token_c" "$job" "$@"

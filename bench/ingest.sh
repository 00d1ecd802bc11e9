#!/usr/bin/env bash
# Upload throughput (issue 35) against two yardsticks on the same machine and the same bytes:
# copying the file on disk, and PostgreSQL's own COPY of the same bytes, in the server's 1 MiB
# chunks, into a table shaped like the one uploads go to: as text (bytea in hex, as psql's \copy
# is mostly used) and in COPY's binary format (no parsing: the fastest way PostgreSQL offers to
# store those rows). Starts a private cluster and a server.
#   bash bench/ingest.sh BUNDLE [BUILD_DIR=build] [RUNS=3]
# COMPRESSION=pglz in the environment sets the chunks' compression back to PostgreSQL's default
# (migration 0009 sets LZ4), for comparison.
# BUNDLE: a survey bundle folder (e.g. `bathyslam simulate --scenario small --out DIR`); its
# pings.csv is the file measured. Prints one line per measurement and the medians.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bundle=$(realpath "$1")
build=$(realpath "${2:-$root/build}")
runs=${3:-3}
source "$root/bench/private_server.sh"
start_private_server --workers 1 --dev-tenant bench

file="$bundle/pings.csv"
bytes=$(stat -c %s "$file")
total=$(du -b --apparent-size -c "$bundle"/*.csv "$bundle"/survey.json | tail -n 1 | cut -f1)
psql=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)/psql
now() { date +%s.%N; }
rate() { /usr/bin/python3 -c "import sys; b, s = int(sys.argv[2]), float(sys.argv[1]); print(f'{s:.2f} s, {b / s / 1e6:.1f} MB/s')" "$1" "${2:-$bytes}"; }

# COPY input: the file in 1 MiB chunks, as the server stores them, each a bytea in hex
# (chunks.copy) and in COPY's binary format (chunks.bin: a header, then per row the field count
# and each field's length and bytes, big-endian; file_id bigint, seq integer, data bytea).
/usr/bin/python3 - "$file" "$work/chunks.copy" "$work/chunks.bin" <<'PY'
import struct, sys
with open(sys.argv[1], "rb") as f, open(sys.argv[2], "w") as text, open(sys.argv[3], "wb") as binary:
    binary.write(b"PGCOPY\n\xff\r\n\0" + struct.pack(">ii", 0, 0))
    seq = 0
    while chunk := f.read(1 << 20):
        text.write(f"1\t{seq}\t\\\\x{chunk.hex()}\n")
        binary.write(struct.pack(">hiqiii", 3, 8, 1, 4, seq, len(chunk)) + chunk)
        seq += 1
    binary.write(struct.pack(">h", -1))
PY
[ -z "${COMPRESSION:-}" ] || "$psql" "$url" -q -c "ALTER TABLE survey_file_chunks ALTER COLUMN data SET COMPRESSION $COMPRESSION"
"$psql" "$url" -q -c "CREATE TABLE ingest_yardstick (LIKE survey_file_chunks INCLUDING ALL)"

declare -a copy_s upload_s pg_s pg_binary_s end_s
for run in $(seq "$runs"); do
  sync
  t0=$(now); cp "$file" "$work/copy"; sync; t1=$(now)
  copy_s+=("$(echo "$t1 - $t0" | bc)")
  rm -f "$work/copy"
  t0=$(now); "$psql" "$url" -q -c "\\copy ingest_yardstick FROM '$work/chunks.copy'"; t1=$(now)
  pg_s+=("$(echo "$t1 - $t0" | bc)")
  "$psql" "$url" -q -c "TRUNCATE ingest_yardstick"
  t0=$(now); "$psql" "$url" -q -c "\\copy ingest_yardstick FROM '$work/chunks.bin' WITH (FORMAT binary)"; t1=$(now)
  pg_binary_s+=("$(echo "$t1 - $t0" | bc)")
  "$psql" "$url" -q -c "TRUNCATE ingest_yardstick"
  # The upload as the server sees it: from CreateSurvey to the last file stored (its SHA-256
  # checked), from the server log's millisecond stamps; finalize's validation is not in it.
  e0=$(now)
  "$build/client/bathyslam" upload "$bundle" --name "ingest-$run" > "$work/upload.out" 2> "$work/upload.err" ||
    { cat "$work/upload.err" >&2; exit 1; }
  e1=$(now)
  end_s+=("$(echo "$e1 - $e0" | bc)")
  survey=$(awk '/^survey .* ready$/ {print $2}' "$work/upload.out")
  read -r t0 t1 < <(/usr/bin/python3 - "$work/server.log" "$survey" <<'PY'
import datetime, re, sys
stamps = []
for line in open(sys.argv[1]):
    if re.search(rf"survey {sys.argv[2]}( created|: .* uploaded)", line):
        stamps.append(datetime.datetime.strptime(line.split()[0], "%Y-%m-%dT%H:%M:%S.%fZ").timestamp())
print(stamps[0], stamps[-1])
PY
)
  upload_s+=("$(echo "$t1 - $t0" | bc)")
  echo "run $run: disk copy $(rate "${copy_s[-1]}"); PostgreSQL COPY $(rate "${pg_s[-1]}"), binary $(rate "${pg_binary_s[-1]}"); bathyslam upload of the bundle $(rate "${upload_s[-1]}" "$total") (end to end with hashing and finalize $(rate "${end_s[-1]}" "$total"))"
done
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
echo "median of $runs, $bytes bytes ($file):"
echo "  disk copy         $(rate "$(median "${copy_s[@]}")")"
echo "  PostgreSQL COPY   $(rate "$(median "${pg_s[@]}")") (text, bytea in hex)"
echo "  PostgreSQL COPY   $(rate "$(median "${pg_binary_s[@]}")") (binary)"
echo "  bathyslam upload  $(rate "$(median "${upload_s[@]}")" "$total") (the bundle, $total bytes, CreateSurvey to the last file stored)"
echo "  end to end        $(rate "$(median "${end_s[@]}")" "$total") (the CLI's wall time: hashing, upload, FinalizeSurvey)"
# The server's peak resident memory over the whole run (issue 35 asks under 300 MB during an upload).
echo "  server peak RSS   $(awk '/VmHWM/ {printf "%.0f MB", $2 / 1024}' "/proc/$server_pid/status")"

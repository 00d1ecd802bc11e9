#!/usr/bin/env bash
# The CLI against a real server and PostgreSQL: an upload cut in the middle and resumed, a gicp
# job submitted, watched and reported, the job limit, tiles and the map downloaded, tokens.
set -euo pipefail
source "$(dirname "$0")/test_database.sh" service_cli
fail() { echo "FAIL: $*" >&2; echo "--- server log" >&2; cat "$work/server.log" >&2; exit 1; }

"$BATHYSLAM_SERVER_BIN" --db "$url" --migrate --listen 127.0.0.1:0 --workers 1 --dev-tenant cli --max-active-jobs 1 \
  > "$work/server.out" 2> "$work/server.log" &
server_pid=$!
for _ in $(seq 100); do grep -q "listening" "$work/server.out" && break; sleep 0.1; done
export BATHYSLAM_SERVER=$(sed -n 's/.*listening on //p' "$work/server.out")
[ -n "$BATHYSLAM_SERVER" ] || fail "server did not start"

# Cut after 3 MB (inside pings.csv), then the same command resumes where the server stopped.
if "$BATHYSLAM" upload "$SMALL_BUNDLE" --stop-after-bytes 3000000 > "$work/up1" 2> "$work/up1.err"; then
  fail "a cut upload reported success"
fi
grep -q "run the same command again to resume" "$work/up1.err" || fail "no resume hint: $(cat "$work/up1.err")"
"$BATHYSLAM" upload "$SMALL_BUNDLE" > "$work/up2" 2> "$work/up2.err" || fail "upload: $(cat "$work/up2.err")"
grep -q "resuming pings.csv at" "$work/up2.err" || fail "did not resume: $(cat "$work/up2.err")"
grep -q "nav.csv *uploaded already" "$work/up2.err" || fail "re-sent nav.csv: $(cat "$work/up2.err")"
survey=$(awk '/^survey .* ready$/ {print $2}' "$work/up2")
[ -n "$survey" ] || fail "no survey id in: $(cat "$work/up2")"

# A .tar of the bundle uploads as the folder does, cut and resumed inside pings.csv too.
tar -cf "$work/small.tar" -C "$(dirname "$SMALL_BUNDLE")" "$(basename "$SMALL_BUNDLE")"
if "$BATHYSLAM" upload "$work/small.tar" --name from-tar --stop-after-bytes 2000000 > /dev/null 2> "$work/tar1.err"; then
  fail "a cut tar upload reported success"
fi
"$BATHYSLAM" upload "$work/small.tar" --name from-tar > "$work/tar2" 2> "$work/tar2.err" || fail "tar upload: $(cat "$work/tar2.err")"
grep -q "resuming pings.csv at" "$work/tar2.err" || fail "tar upload did not resume: $(cat "$work/tar2.err")"
grep -Eq "^survey [0-9]+ ready$" "$work/tar2" || fail "$(cat "$work/tar2")"
# A tar whose pings.csv is a symbolic link is refused naming the member, before any call: its
# bytes are not in the tar, and GDAL offered the headers after it, hashed but never sent.
mkdir "$work/linked"
cp "$SMALL_BUNDLE/survey.json" "$SMALL_BUNDLE/nav.csv" "$work/linked/"
ln -s "../small.tar" "$work/linked/pings.csv"
tar -cf "$work/linked.tar" -C "$work" linked
if "$BATHYSLAM" upload "$work/linked.tar" --name linked > /dev/null 2> "$work/linked.err"; then
  fail "a tar with a symbolic link was uploaded"
fi
grep -q "linked.tar: 'linked/pings.csv' is a symbolic link to '../small.tar'" "$work/linked.err" || fail "$(cat "$work/linked.err")"
grep -q "'linked'" "$work/server.log" && fail "a survey was created for a refused tar"

if "$BATHYSLAM" submit "$survey" --config gicp --set registration.gicp.max_iterations=0 2> "$work/bad.err"; then
  fail "an out-of-range parameter was accepted"
fi
grep -q "INVALID_ARGUMENT: parameters\[registration.gicp.max_iterations\]" "$work/bad.err" || fail "$(cat "$work/bad.err")"

job=$("$BATHYSLAM" submit "$survey" --config gicp | awk '/^job/ {print $2}')
# One active job per tenant on this server: a second one while the first runs is refused.
if "$BATHYSLAM" submit "$survey" --config odometry 2> "$work/limit.err"; then fail "over the job limit"; fi
grep -q "RESOURCE_EXHAUSTED" "$work/limit.err" || fail "$(cat "$work/limit.err")"
"$BATHYSLAM" watch "$job" > "$work/watch" 2> "$work/watch.err" || fail "watch: $(cat "$work/watch" "$work/watch.err")"
grep -q "job $job succeeded" "$work/watch" || fail "$(cat "$work/watch")"
for stage in load submaps register graph eval map store; do
  grep -q "  $stage " "$work/watch.err" || fail "no progress bar for $stage"
done

"$BATHYSLAM" report "$job" --out "$work/report" > "$work/table" || fail "report"
grep -q "^safety net: " "$work/table" || fail "the report table has no safety-net verdict"
grep -q "^consistency " "$work/table" && grep -q "^adjacent " "$work/table" || fail "$(cat "$work/table")"
for png in consistency_histogram trajectory_error trajectory; do
  [ "$(head -c 4 "$work/report/$png.png" | tail -c 3)" = "PNG" ] || fail "$png.png is not a PNG"
done
"$BATHYSLAM" report "$job" --json | python3 -c 'import json, sys; r = json.load(sys.stdin); assert r["configuration"] == "gicp"'
"$BATHYSLAM" jobs | grep -Eq "^ +$job +$survey +gicp +succeeded" || fail "jobs: $("$BATHYSLAM" jobs)"

# A site: created, a survey added (not twice), listed, a job submitted by it and listed by it.
site=$("$BATHYSLAM" site create harbour | awk '/^site/ {print $2}')
"$BATHYSLAM" site add "$site" "$survey" | grep -q "surveys $survey " || fail "site add"
if "$BATHYSLAM" site add "$site" "$survey" 2> "$work/twice.err"; then fail "a survey added to a site twice"; fi
grep -q "INVALID_ARGUMENT: survey_ids\[0\]: survey $survey is in site $site already" "$work/twice.err" || fail "$(cat "$work/twice.err")"
"$BATHYSLAM" site list | grep -Eq "^ +$site +.* harbour +$survey$" || fail "site list: $("$BATHYSLAM" site list)"
site_job=$("$BATHYSLAM" submit --site "$site" --config odometry | awk '/^job/ {print $2}')
"$BATHYSLAM" watch "$site_job" > /dev/null 2>&1 || fail "the site's job"
"$BATHYSLAM" jobs --site "$site" | grep -Eq "^ +$site_job +$survey +odometry +succeeded" || fail "jobs --site"
[ "$("$BATHYSLAM" jobs --site "$site" | wc -l)" = 2 ] || fail "jobs --site lists other jobs: $("$BATHYSLAM" jobs --site "$site")"

# The map: every tile, then those meeting a box around one tile's centre; the whole map as a COG
# and as a BAG.
"$BATHYSLAM" tiles "$job" --out "$work/tiles" > "$work/tiles.out" || fail "tiles"
all=$(awk '{print $1}' "$work/tiles.out")
[ "$all" -gt 1 ] || fail "$(cat "$work/tiles.out")"
first=$(cd "$work/tiles" && ls 0/*.tif | head -n 1)
gdalinfo "$work/tiles/$first" | grep -q "Band 3" || fail "GDAL cannot read $first"
col_row=$(basename "$first" .tif)
e=$(( ${col_row%_*} * 256 + 128 )) n=$(( ${col_row#*_} * 256 + 128 ))
"$BATHYSLAM" tiles "$job" --out "$work/box" --bbox $e $n $((e + 1)) $((n + 1)) | grep -q "^[1-9][0-9]* geotiff tiles" ||
  fail "no tile in the box"
[ -f "$work/box/$first" ] || fail "the box did not fetch $first"
[ "$(find "$work/box" -name '*.tif' | wc -l)" -lt "$all" ] || fail "the box fetched every tile"
"$BATHYSLAM" map "$job" --out "$work/map.tif" > /dev/null || fail "map"
gdalinfo "$work/map.tif" | grep -q "LAYOUT=COG" || fail "map.tif is not a COG"
# A file name without a folder is written where the command runs.
(cd "$work" && "$BATHYSLAM" map "$job" --out here.tif > /dev/null 2> "$work/here.err") || fail "map --out here.tif: $(cat "$work/here.err")"
cmp "$work/here.tif" "$work/map.tif" || fail "here.tif differs from map.tif"
"$BATHYSLAM" map "$job" --format bag --out "$work/map.bag" > /dev/null || fail "map --format bag"
gdalinfo "$work/map.bag" | grep -q "^Driver: BAG" || fail "map.bag is not a BAG"
gdalinfo "$work/map.bag" | grep -q "UTM zone 51N" || fail "map.bag lacks the survey's CRS"
[ "$(gdalinfo "$work/map.bag" | grep '^Size is')" = "$(gdalinfo "$work/map.tif" | grep '^Size is')" ] ||
  fail "map.bag and map.tif differ in size"
[ -f "$work/report/map_difference.png" ] || fail "no map difference plot"

# The survey's pings with the corrected navigation as GSF: every ping, moved off dead reckoning
# (the DR survey as GSF differs), and the very file `process --export-gsf` writes for the same
# bundle and configuration.
"$BATHYSLAM" map "$job" --format gsf --out "$work/corrected.gsf" > /dev/null || fail "map --format gsf"
"$BATHYSLAM" inspect "$work/corrected.gsf" > "$work/corrected.txt" || fail "inspect: $(cat "$work/corrected.txt")"
pings=$(awk '/^counts/ {print $2}' "$work/corrected.txt")
[ "$pings" = "$(awk '/^counts/ {print $2}' <("$BATHYSLAM" inspect "$SMALL_BUNDLE"))" ] || fail "corrected.gsf: $pings pings"
"$BATHYSLAM" simulate --scenario small --seed 1 --format gsf --out "$work/drgsf" > /dev/null
extent() { grep -E "^(  latitude|  longitude|extent) " "$1"; }
"$BATHYSLAM" inspect "$work/drgsf/survey.gsf" > "$work/dr.txt"
[ "$(extent "$work/dr.txt" | wc -l)" = 3 ] && [ "$(extent "$work/dr.txt")" != "$(extent "$work/corrected.txt")" ] ||
  fail "corrected.gsf has the dead-reckoning positions: $(extent "$work/corrected.txt")"
"$BATHYSLAM" process "$SMALL_BUNDLE" --config gicp --export-gsf --out "$work/process" > /dev/null 2>&1 || fail "process"
cmp "$work/corrected.gsf" "$work/process/corrected.gsf" || fail "the job's corrected.gsf differs from process's"

# GSF: a real file uploads and finalizes (EX1811 is 6.1 km x 6.4 km of deep water, mapped at the
# 64 m its soundings fill); a truncated one is refused naming its record and byte; a simulated
# GSF survey with its reference navigation runs as a job. (A survey too large to map is refused
# at finalize naming its extent: service_hostile_input.)
"$BATHYSLAM" upload "$GSF_DATA/EX1811_EM302_0059_20181102_212138.gsf" --name real-gsf \
  > "$work/gsf1" 2> "$work/gsf1.err" || fail "GSF upload: $(cat "$work/gsf1.err")"
grep -Eq "^survey [0-9]+ ready$" "$work/gsf1" || fail "$(cat "$work/gsf1")"
# A real file has no reference navigation and one submap: the report says what it could not
# compute and why, not a zero error.
real_job=$("$BATHYSLAM" submit "$(awk '/^survey .* ready$/ {print $2}' "$work/gsf1")" --config odometry | awk '/^job/ {print $2}')
"$BATHYSLAM" watch "$real_job" > "$work/real_watch" 2> /dev/null || fail "watch: $(cat "$work/real_watch")"
"$BATHYSLAM" report "$real_job" > "$work/real_report" || fail "report of the real GSF job"
grep -q "^trajectory  *not computed: no reference navigation$" "$work/real_report" || fail "$(cat "$work/real_report")"
grep -q "^consistency  *not computed: no map cell seen by two survey lines" "$work/real_report" || fail "$(cat "$work/real_report")"
# A Kongsberg EM .all file uploads, finalizes and runs as a job, its corrected GSF at its depths.
"$BATHYSLAM" upload "$ALL_DATA/0243_P007_MBES_EM122_20150207_044356_Supporter_GA4430.all" --name real-all \
  > "$work/all1" 2> "$work/all1.err" || fail ".all upload: $(cat "$work/all1.err")"
all_job=$("$BATHYSLAM" submit "$(awk '/^survey .* ready$/ {print $2}' "$work/all1")" --config mchs | awk '/^job/ {print $2}')
"$BATHYSLAM" watch "$all_job" > "$work/all_watch" 2> /dev/null || fail "watch: $(cat "$work/all_watch")"
grep -q "job $all_job succeeded" "$work/all_watch" || fail "$(cat "$work/all_watch")"
"$BATHYSLAM" map "$all_job" --format gsf --out "$work/all_job.gsf" > /dev/null || fail "map --format gsf of the .all job"
"$BATHYSLAM" inspect "$work/all_job.gsf" | grep -q "depth       3479.9 .. 3661.1 m" || fail "the .all job's corrected GSF"
# An XTF file (R2Sonic via QINSy) the same way: 923 pings in, 923 pings with corrected navigation out.
"$BATHYSLAM" upload "$XTF_DATA/0009_150708_R2Testing_0001.xtf" --name real-xtf \
  > "$work/xtf1" 2> "$work/xtf1.err" || fail ".xtf upload: $(cat "$work/xtf1.err")"
xtf_job=$("$BATHYSLAM" submit "$(awk '/^survey .* ready$/ {print $2}' "$work/xtf1")" --config mchs | awk '/^job/ {print $2}')
"$BATHYSLAM" watch "$xtf_job" > "$work/xtf_watch" 2> /dev/null || fail "watch: $(cat "$work/xtf_watch")"
grep -q "job $xtf_job succeeded" "$work/xtf_watch" || fail "$(cat "$work/xtf_watch")"
"$BATHYSLAM" map "$xtf_job" --format gsf --out "$work/xtf_job.gsf" > /dev/null || fail "map --format gsf of the .xtf job"
"$BATHYSLAM" inspect "$work/xtf_job.gsf" | grep -q "^  pings  *923 " || fail "the .xtf job's corrected GSF: $("$BATHYSLAM" inspect "$work/xtf_job.gsf")"
head -c 5000 "$GSF_DATA/gsfpy_test_data.gsf" > "$work/cut.gsf"
if "$BATHYSLAM" upload "$work/cut.gsf" 2> "$work/cut.err"; then fail "a truncated GSF file was accepted"; fi
grep -q "cut.gsf: record 7 at byte 4000: truncated" "$work/cut.err" || fail "$(cat "$work/cut.err")"
"$BATHYSLAM" simulate --scenario small --seed 4 --format gsf --out "$work/simgsf" > /dev/null
"$BATHYSLAM" upload "$work/simgsf/survey.gsf" --reference-nav "$work/simgsf/reference_nav.csv" --name sim-gsf \
  > "$work/gsf2" 2> "$work/gsf2.err" || fail "GSF upload: $(cat "$work/gsf2.err")"
gsf_survey=$(awk '/^survey .* ready$/ {print $2}' "$work/gsf2")
gsf_job=$("$BATHYSLAM" submit "$gsf_survey" --config odometry | awk '/^job/ {print $2}')
"$BATHYSLAM" watch "$gsf_job" > "$work/gsf_watch" 2> /dev/null || fail "watch: $(cat "$work/gsf_watch")"
grep -q "job $gsf_job succeeded" "$work/gsf_watch" || fail "$(cat "$work/gsf_watch")"
"$BATHYSLAM" report "$gsf_job" --json | /usr/bin/python3 -c '
import json, sys
r = json.load(sys.stdin)
assert r["trajectory_error_m"]["optimized"]["rmse"] > 0, r["trajectory_error_m"]' || fail "GSF job report"
"$BATHYSLAM" map "$gsf_job" --format bag --out "$work/gsf.bag" > /dev/null || fail "map --format bag of the GSF job"
gdalinfo "$work/gsf.bag" | grep -q "UTM zone 51N" || fail "the GSF job's BAG is not in the data's UTM zone"
"$BATHYSLAM" map "$gsf_job" --format gsf --out "$work/gsf_job.gsf" > /dev/null || fail "map --format gsf of the GSF job"
[ "$("$BATHYSLAM" inspect "$work/gsf_job.gsf" | awk '/^  pings/ {print $2}')" = \
  "$("$BATHYSLAM" inspect "$work/simgsf/survey.gsf" | awk '/^  pings/ {print $2}')" ] || fail "the GSF job's GSF lost pings"

# Tokens: another tenant sees none of this; a wrong token is refused.
token=$("$BATHYSLAM_SERVER_BIN" token --db "$url" --tenant other)
[ "$(BATHYSLAM_TOKEN=$token "$BATHYSLAM" jobs | wc -l)" = 1 ] || fail "another tenant sees jobs"
if BATHYSLAM_TOKEN=bst_wrong "$BATHYSLAM" jobs 2> "$work/auth.err"; then fail "a wrong token was accepted"; fi
grep -q "UNAUTHENTICATED" "$work/auth.err" || fail "$(cat "$work/auth.err")"

# An operator lists tokens (never the secret) and revokes one by its id: refused from then on.
ci=$("$BATHYSLAM_SERVER_BIN" token create --db "$url" --tenant other --description "ci runner")
BATHYSLAM_TOKEN=$ci "$BATHYSLAM" jobs > /dev/null || fail "a new token was refused"
"$BATHYSLAM_SERVER_BIN" token list --db "$url" --tenant other > "$work/tokens" || fail "token list"
grep -q "$ci\|$token" "$work/tokens" && fail "token list shows a secret: $(cat "$work/tokens")"
id=$(awk '/ci runner$/ {print $1}' "$work/tokens")
[ -n "$id" ] && [ "$(grep -c ' other ' "$work/tokens")" = 2 ] || fail "$(cat "$work/tokens")"
"$BATHYSLAM_SERVER_BIN" token revoke --db "$url" --id "$id" > /dev/null || fail "token revoke"
if BATHYSLAM_TOKEN=$ci "$BATHYSLAM" jobs 2> "$work/revoked.err"; then fail "a revoked token was accepted"; fi
grep -q "UNAUTHENTICATED" "$work/revoked.err" || fail "$(cat "$work/revoked.err")"
BATHYSLAM_TOKEN=$token "$BATHYSLAM" jobs > /dev/null || fail "revoking one token revoked another"
if "$BATHYSLAM_SERVER_BIN" token revoke --db "$url" --id "$id" 2> /dev/null; then fail "revoked twice"; fi
# An expiry is more than 0 days: 0 is refused (it made a token that never expired); leaving the
# option out is how to ask for one that never does.
if "$BATHYSLAM_SERVER_BIN" token create --db "$url" --tenant other --expires-in-days 0 > /dev/null 2> "$work/zero.err"; then
  fail "a token expiring in 0 days was issued"
fi
grep -q "leave the option out for a token that never expires" "$work/zero.err" || fail "$(cat "$work/zero.err")"
half=$("$BATHYSLAM_SERVER_BIN" token create --db "$url" --tenant other --description "half a day" --expires-in-days 0.5)
BATHYSLAM_TOKEN=$half "$BATHYSLAM" jobs > /dev/null || fail "a token valid for half a day was refused"
"$BATHYSLAM_SERVER_BIN" token list --db "$url" --tenant other | grep "half a day$" | grep -q never && fail "0.5 days never expires"
echo "service cli: ok"

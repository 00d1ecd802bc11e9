#!/usr/bin/env bash
# Builds a survey bundle libFuzzer target with Debian's clang (ASan + UBSan) and runs it for a
# bounded time. Exit 0: no crash, leak or sanitizer report.
#   scripts/fuzz-bundle.sh BUILD_DIR [SECONDS] [TARGET]
# TARGET bundle_reader (the default): the parsers of nav.csv, pings.csv and survey.json, from the
# seed corpus in tests/fuzz/bundle_corpus. tar: a bundle given as a .tar (its headers, GDAL's
# /vsitar/, every file read through), from seed tars made here of the same corpus: ustar, pax,
# GNU long names, a symbolic link.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${2:-60}
target=${3:-bundle_reader}
out=$(realpath -m "$1")/fuzz-${target/bundle_reader/bundle}
mkdir -p "$out/corpus" "$out/new"
sources=(core/io/bundle_reader.cpp core/io/csv.cpp core/io/byte_source.cpp core/io/bounded_json.cpp core/io/problem.cpp
         core/io/crs.cpp core/io/bundle_files.cpp core/io/tar_members.cpp)
case "$target" in
  bundle_reader) fuzz=bundle_reader_fuzz max_len=4096 ;;
  tar) fuzz=tar_bundle_fuzz max_len=65536 ;;
  *) echo "unknown target $target (bundle_reader or tar)" >&2; exit 2 ;;
esac
clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -I"$root" -I/usr/include/gdal \
  "$root/tests/fuzz/$fuzz.cpp" "${sources[@]/#/$root/}" -lproj -lgdal -o "$out/$fuzz"
if [ "$target" = tar ]; then
  bundle="$out/seed/a bundle"
  mkdir -p "$bundle" "$out/seed/$(printf 'long%.0s' {1..30})"
  # The corpus files without their first byte (the parser selector of bundle_reader_fuzz).
  for pair in nav:nav.csv pings:pings.csv survey_json:survey.json; do
    tail -c +2 "$root/tests/fuzz/bundle_corpus/${pair%%:*}" > "$bundle/${pair#*:}"
  done
  cp "$bundle"/* "$out/seed/$(printf 'long%.0s' {1..30})/"
  rm -f "$out/seed/a bundle/reference_nav.csv"
  (cd "$out/seed" && tar --format=ustar -cf "$out/corpus/ustar.tar" "a bundle/survey.json" "a bundle/nav.csv" "a bundle/pings.csv" &&
     tar --format=pax -cf "$out/corpus/pax.tar" "a bundle" &&
     tar --format=gnu -cf "$out/corpus/gnu-long.tar" "$(printf 'long%.0s' {1..30})" &&
     ln -sf nav.csv "a bundle/reference_nav.csv" &&
     tar --format=gnu -cf "$out/corpus/symlink.tar" "a bundle")
else
  cp -rn "$root"/tests/fuzz/bundle_corpus/* "$out/corpus/"
fi
# New inputs go to a scratch corpus; the seeds stay as they are.
"$out/$fuzz" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$out/new" "$out/corpus"

#!/usr/bin/env bash
# The unit and storage tests again, built with AddressSanitizer and UndefinedBehaviorSanitizer
# (BATHYSLAM_SANITIZE) into build-sanitize/ (or $SANITIZE_BUILD_DIR): memory errors, leaks and undefined behaviour fail
# the test that meets them. scripts/test.sh runs this after the ordinary build's tests.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
dir=${SANITIZE_BUILD_DIR:-build-sanitize}
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DBATHYSLAM_SANITIZE=ON -DBATHYSLAM_BENCHMARKS=OFF > /dev/null
cmake --build "$dir" -j"${JOBS:-$(nproc)}" --target unit_and_storage_tests
cd "$dir"
# UBSan only reports by default; halting makes a report a failure. Leaks are checked (ASan's
# default); third-party libraries' own leaks at exit are listed in scripts/lsan.supp.
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0
export LSAN_OPTIONS=suppressions=$root/scripts/lsan.supp:print_suppressions=0
ctest --output-on-failure --timeout 900 -j"${JOBS:-$(nproc)}" -L "unit|storage"

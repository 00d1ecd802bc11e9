#!/usr/bin/env bash
# Installs every Debian 12 package bathyslam needs to build, test and run. Idempotent.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git ca-certificates
  clang libclang-rt-14-dev  # the GSF reader's libFuzzer target (scripts/fuzz-sonar.sh gsf)
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc
  libeigen3-dev libpcl-dev libceres-dev libopencv-dev
  libpq-dev postgresql postgresql-contrib
  libopenvdb-dev libgdal-dev gdal-bin libproj-dev proj-data proj-bin
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev libssl-dev zlib1g-dev libzstd-dev libtbb-dev
  openssl  # service_tls makes its certificates at test time
  libcpp-httplib-dev  # the HTTP endpoint (server/http)
  chromium python3-websocket  # the web page's test drives headless Chromium over DevTools
  clang libclang-rt-14-dev  # libFuzzer (scripts/fuzz-*.sh)
  python3 python3-grpcio python3-protobuf python3-gdal python3-openvdb python3-numpy
  python3-imath  # ships the PyImath library that Imath's CMake targets (via OpenVDB) reference
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"

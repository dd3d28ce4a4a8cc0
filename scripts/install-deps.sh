#!/usr/bin/env bash
# Installs every Debian 12 package pathfarm needs to build, test and run. Idempotent: apt-get runs only
# when something is missing. This is the complete list; nothing else is assumed on the machine.
set -euo pipefail

BUILD_PACKAGES=(
  build-essential cmake ninja-build pkg-config ccache clang-format
  libembree-dev          # ray tracing kernels (Embree 3)
  libopenexr-dev         # EXR images (OpenEXR 3)
  libstb-dev             # PNG/JPEG read and write
  libpugixml-dev         # Mitsuba XML
  libtinyobjloader-dev   # OBJ meshes
  zlib1g-dev             # Mitsuba .serialized meshes
  libcli11-dev           # command line
  libspdlog-dev          # logging
  libtbb-dev             # task scheduling
  nlohmann-json3-dev     # JSON status
  libcpp-httplib-dev     # HTTP status endpoint
  libsqlite3-dev         # job store
  libxxhash-dev libzstd-dev                            # content hashes, compressed transfers
  libboost-dev           # Sobol direction numbers (Joe and Kuo 2008) from Boost.Random's table
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc   # farm RPC
  openssl                # certificates for the farm's TLS test
  libgtest-dev libgmock-dev libbenchmark-dev           # tests and benchmarks
  chromium fonts-dejavu-core   # the dashboard test loads the page in headless Chromium (with a font for its text)
  iproute2                     # the multi-host test and deploy/netns build hosts from network namespaces
  clang libclang-rt-14-dev     # the libFuzzer targets (fuzz/, build-fuzz): clang and its fuzzer/sanitizer runtimes
)

missing=()
for p in "${BUILD_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

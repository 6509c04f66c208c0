#!/usr/bin/env bash
# One entry point for a fresh Debian machine: installs what is missing, configures,
# builds, then runs the demo or the tests.
#
#   tools/dev.sh demo [floorpose demo options]   build, then run `floorpose demo`
#   tools/dev.sh test [ctest options]            build, then run every test suite
#   tools/dev.sh build                           just install, configure and build
#
# BUILD_DIR (default: build) and BUILD_TYPE (default: RelWithDebInfo) may be set.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake pkg-config clang-format
  cyclonedds-dev cyclonedds-tools libprotobuf-dev protobuf-compiler libeigen3-dev
  libspdlog-dev libgtest-dev libgmock-dev libbenchmark-dev libsystemd-dev
  libcli11-dev nlohmann-json3-dev libyaml-cpp-dev libpng-dev libgdal-dev libproj-dev libcpp-httplib-dev systemd)
# The tests also talk to clients that are not ours (label interop): a Fast DDS app and
# the Python example client. The fuzz tests (label fuzz, tools/fuzz.sh) build with clang
# and its libFuzzer and sanitizer runtimes; the security tests make their CA and
# identities with openssl (tools/make-dds-security.sh); the dashboard test (label browser)
# drives Debian's headless Chromium through chromedriver; the package test (label package,
# tools/check-package.sh) runs lintian and man on the .deb; the CoT test receives as a TAK
# client would, with Node.js and @tak-ps/node-cot from the npm registry.
if [ "${1:-build}" = test ]; then
  packages+=(libfastrtps-dev fastddsgen python3-protobuf clang libclang-rt-14-dev openssl
    chromium chromium-driver lintian man-db)
  command -v npm >/dev/null || packages+=(nodejs npm)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "dev.sh: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

build_dir=${BUILD_DIR:-build}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-RelWithDebInfo}" >/dev/null
cmake --build "$build_dir" -j"$(nproc)"

cmd=${1:-build}
shift || true
# The TAK client library of the CoT test, into the build directory (never the repository),
# at the version that runs on Debian's and NodeSource's Node.js 20.
if [ "$cmd" = test ] && [ ! -f "$build_dir/npm/node_modules/@tak-ps/node-cot/package.json" ]; then
  mkdir -p "$build_dir/npm"
  (cd "$build_dir/npm" && npm install --no-audit --no-fund --no-save --loglevel=error \
    @tak-ps/node-cot@13.1.0)
fi
case "$cmd" in
  demo) exec "$build_dir/tools/floorpose" demo "$@" ;;
  test) exec ctest --test-dir "$build_dir" --output-on-failure -j"$(nproc)" "$@" ;;
  build) ;;
  *) echo "usage: tools/dev.sh demo|test|build" >&2; exit 2 ;;
esac

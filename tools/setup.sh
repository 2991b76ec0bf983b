#!/usr/bin/env bash
# Sets up a fresh Debian machine for Refit and builds it.
#   bash tools/setup.sh          install packages, configure and build (Release)
#   bash tools/setup.sh demo     ... then run `refit demo` and say where its output is
#   bash tools/setup.sh test     ... then run the whole test suite through CTest, again under the
#                                sanitizers, and each fuzz target for 30 s
# Installing is idempotent and quiet when every package is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake ninja-build g++ pkg-config libtbb-dev libeigen3-dev libembree-dev
          libgtest-dev libgmock-dev libbenchmark-dev libnanoflann-dev nlohmann-json3-dev libstb-dev
          libcli11-dev python3-numpy python3-scipy clang libclang-rt-14-dev
          pybind11-dev python3-dev python3-pytest libcsv-dev python3-distributed blender
          python3-ezdxf librsvg2-bin)
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

jobs=$(nproc)
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
# `import refit` in Debian's Python and in Blender (which runs it): a .pth file in its
# site folder names the build tree's package (`cmake --install` copies it instead).
if [ -f build/release/python/refit/__init__.py ]; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  $sudo mkdir -p "$site"
  echo "$PWD/build/release/python" | $sudo tee "$site/refit-build.pth" >/dev/null
fi

case "${1:-build}" in
  build) ;;
  demo)
    out="${2:-demo-output}"
    build/release/tools/refit demo --out-dir "$out"
    echo "demo output: $(cd "$out" && pwd)"
    ;;
  test)
    ctest --preset release -j "$jobs"
    # The same suite under AddressSanitizer and UBSan, built by clang with
    # libFuzzer's edge coverage in the engine (not in the tests) so that the same
    # build also runs each fuzz target for 30 s (tests/fuzz/; bench/fuzz.sh runs
    # them longer, with comparison tracing too): one build less than a separate
    # fuzz tree. The sanitize preset leaves out three large cases
    # (CMakePresets.json: 230 of its 640 test-seconds, brute-force scans and a
    # 100k-agent solve whose code the smaller cases run too); the release pass runs them.
    cmake --preset sanitize >/dev/null
    cmake --build --preset sanitize -j "$jobs"
    ctest --preset sanitize -j "$jobs"
    ;;
  *) echo "usage: tools/setup.sh [build|demo [DIR]|test]" >&2; exit 2 ;;
esac

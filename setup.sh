#!/usr/bin/env bash
# bvhlab set-up on a fresh Debian 12 machine (as root, or with sudo available).
#   bash setup.sh main   install, fetch datasets, build, run the default experiment (writes a report)
#   bash setup.sh test   install, fetch datasets, build, run every test (CTest)
#   bash setup.sh deps   install Debian packages only
#   bash setup.sh build  configure + build only
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libglm-dev libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri
  libopenmesh-dev libcgal-dev libbenchmark-dev libgtest-dev libopenimageio-dev libembree-dev
  libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libglfw3-dev libimgui-dev
  python3-glad glslang-tools python3 python3-matplotlib python3-numpy xvfb xauth
)

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

deps() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}"
    as_root apt-get update -qq
    DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

build() {
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j "$(nproc)"
}

case "${1:-}" in
  deps) deps ;;
  build) deps; build ;;
  test)
    deps; bash datasets/fetch.sh; build
    # 2 llvmpipe threads per render and 2 test processes at once would oversubscribe 2 cores.
    ctest --test-dir build --output-on-failure -j 1 ;;
  main)
    deps; bash datasets/fetch.sh; build
    if [ -f experiments/configs/quick.toml ] && ./build/bvhlab run --help >/dev/null 2>&1; then
      ./build/bvhlab run experiments/configs/quick.toml --out results/quick
      echo "report: results/quick/report.html"
    else
      mkdir -p out
      ./build/bvhlab render datasets/scenes/report.toml -o out/report.png --width 1280 --height 720
      echo "image: out/report.png"
    fi ;;
  *) echo "usage: bash setup.sh main|test|deps|build" >&2; exit 2 ;;
esac

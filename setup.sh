#!/usr/bin/env bash
# bvhlab set-up on a fresh Debian 12 machine (as root, or with sudo available).
#   bash setup.sh main   install, fetch datasets, build, run the default experiment (writes a report)
#   bash setup.sh test   install, fetch datasets, build, run every test (CTest)
#   bash setup.sh deps   install Debian packages only
#   bash setup.sh build  configure + build only
#   bash setup.sh sanitize        ASan + UBSan build (clang, build-sanitize/), run the CPU tests and the GLSL-vs-mirror
#                                 and trace tests on llvmpipe (ctest -L '^(cpu|gl-asan)$')
#   bash setup.sh fuzz [SECONDS]  libFuzzer targets for every file parser and importer, SECONDS each
#                                 (default 60), off the same build; exits 1 on a finding and prints its
#                                 reproducer (tests/fuzz/run.sh)
# CI (.ci/run) runs test, then sanitize, then fuzz 150 (FUZZ_SEED=1, FUZZ_RUNS=1000: the time is a cap).
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libglm-dev libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri
  libopenmesh-dev libcgal-dev libbenchmark-dev libgtest-dev libopenimageio-dev libembree-dev libassimp-dev libpugixml-dev
  libtomlplusplus-dev nlohmann-json3-dev libcli11-dev libglfw3-dev libimgui-dev
  python3-glad glslang-tools python3 python3-matplotlib python3-numpy xvfb xauth
)

# Only for `sanitize` and `fuzz`: clang with its sanitizer and libFuzzer runtimes, llvm-symbolizer.
CHECK_PACKAGES=(clang libclang-rt-14-dev llvm-14)

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

deps() {
  local missing=()
  for p in "${PACKAGES[@]}" "$@"; do
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

# One instrumented build serves both checks: every library is compiled once with ASan + UBSan and
# libFuzzer's coverage hooks (-DBVHLAB_FUZZ=ON); `sanitize` links the CPU test executables, `fuzz` the
# fuzz targets. -O1 with line tables keeps reports readable; NDEBUG as in the Release build (bvhlab has
# no assert(); toml++'s debug-only assertions are not what ships).
sanitize_build() {
  local flags="-O1 -gline-tables-only -DNDEBUG"
  cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
        "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$flags" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$flags" \
        -DBVHLAB_FUZZ=ON -DBVHLAB_BENCHMARKS=OFF >/dev/null
  cmake --build build-sanitize -j "$(nproc)" --target "$@"
}
sanitizer_env() {  # for the CPU tests (tests/fuzz/run.sh sets its own, lighter options)
  # Third-party leaks LeakSanitizer must not fail on are listed, with why, in tests/fuzz/lsan.supp.
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1}
  export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  if [ -x /usr/lib/llvm-14/bin/llvm-symbolizer ]; then export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer; fi
}

case "${1:-}" in
  deps) deps ;;
  build) deps; build ;;
  test)
    deps; bash datasets/fetch.sh; build
    # One test process per core. A GL test's llvmpipe draws on every core, so two at once share them,
    # but no test asserts a time, and much of a GL test is single-threaded (shader compiles, set-up):
    # on the 2-core machine the 966 tests took 518 s with -j 2, against 933 s one at a time (a run that
    # shared the machine with a build: its tests' own times add up to 932 s).
    ctest --test-dir build --output-on-failure -j "$(nproc)" ;;
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
  sanitize)
    deps "${CHECK_PACKAGES[@]}"; bash datasets/fetch.sh; sanitize_build cpu_tests gl_asan_tests
    sanitizer_env
    # The tests labelled "cpu" (tests/CMakeLists.txt) and, of the GL tests, those labelled "gl-asan":
    # the GLSL kernels against their C++ mirrors and the trace path on llvmpipe (our code instrumented,
    # Mesa not). Cost measured on the 2-core machine: tests/fuzz/README.md. Not the other GL tests, and
    # not the "cpu-slow" scale tests (run those with: ctest --test-dir build-sanitize -L cpu).
    # One CTest test per executable here (tests/CMakeLists.txt says why); a failure names its gtest case.
    ctest --test-dir build-sanitize -L '^(cpu|gl-asan)$' --output-on-failure -j "$(nproc)" ;;
  fuzz)
    deps "${CHECK_PACKAGES[@]}"; bash datasets/fetch.sh; sanitize_build fuzz_targets
    if [ -x /usr/lib/llvm-14/bin/llvm-symbolizer ]; then export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer; fi
    bash tests/fuzz/run.sh build-sanitize "${2:-60}" ;;
  *) echo "usage: bash setup.sh main|test|deps|build|sanitize|fuzz [SECONDS]" >&2; exit 2 ;;
esac

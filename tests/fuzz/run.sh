#!/usr/bin/env bash
# Runs every libFuzzer target of a -DBVHLAB_FUZZ=ON build for SECONDS each (bash setup.sh fuzz [SECONDS]).
#   bash tests/fuzz/run.sh BUILD_DIR [SECONDS] [PARSER...]
# Corpora grow in BUILD_DIR/fuzz/corpus/PARSER (kept between runs); each run first adds the seeds:
# tests/fuzz/seeds/PARSER, the repository's own small files of that kind (datasets/, tests/, experiments/,
# copied at run time, at most 64 KiB each) and the fixed regressions (tests/fuzz/regressions/PARSER).
# A finding (crash, ASan/UBSan report, hang over -timeout, memory over -rss_limit_mb, broken invariant)
# is written to BUILD_DIR/fuzz/artifacts/PARSER/ and makes this script exit 1, printing the reproducer
# path and the report. Replay one: BUILD_DIR/tests/fuzz/fuzz_PARSER FILE
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:?usage: run.sh BUILD_DIR [SECONDS] [PARSER...]}" && pwd)
seconds=${2:-60}
shift $(( $# >= 2 ? 2 : 1 ))
parsers=("$@")
if [ ${#parsers[@]} -eq 0 ]; then  # every target: one tests/fuzz/fuzz_PARSER.cpp each (as CMake globs them)
  for f in "$root"/tests/fuzz/fuzz_*.cpp; do f=${f##*/fuzz_}; parsers+=("${f%.cpp}"); done
fi
work=$build/fuzz
jobs=${FUZZ_JOBS:-$(nproc)}

# Repository files that seed each parser (globs relative to the repository root).
seed_globs() {
  case $1 in
    obj) echo "datasets/hard/meshes/*.obj datasets/cache/meshes/*.obj tests/fixtures/*/*.obj" ;;
    off) echo "datasets/cache/meshes/*.off tests/fixtures/*/*.off" ;;
    ply) echo "datasets/cache/meshes/*.ply tests/fixtures/*/*.ply" ;;
    stl) echo "datasets/cache/meshes/*.stl tests/fixtures/*/*.stl" ;;
    gltf|glb|dae|ac|3ds|fbx)  # the assimp formats (hand-written seeds in seeds/PARSER; big models skipped)
      echo "datasets/cache/meshes/*.$1 datasets/scenes/*.$1 datasets/scenes/*/*.$1 tests/fixtures/*/*.$1" ;;
    scene) echo "datasets/scenes/*.toml datasets/hard/*.toml" ;;
    config) echo "experiments/configs/*.toml tests/fixtures/experiments/*.toml" ;;
    camera_path) echo "experiments/configs/paths/*.txt" ;;
    viewer_script) echo "experiments/configs/paths/*.script" ;;
    png|jpeg|exr|hdr)  # textures and worlds (seeds/PARSER: tiny files written by OpenImageIO; big maps skipped)
      echo "datasets/cache/*/*.$1 datasets/scenes/*.$1 datasets/scenes/*/*.$1 tests/fixtures/*/*.$1" ;;
  esac
}

prepare() {  # PARSER: fill the corpus
  local p=$1 corpus=$work/corpus/$1 f
  mkdir -p "$corpus" "$work/artifacts/$p" "$work/logs"
  for f in $(cd "$root" && eval "ls -d $(seed_globs "$p") 2>/dev/null") \
           tests/fuzz/seeds/"$p"/* tests/fuzz/regressions/"$p"/*; do
    f=$root/$f
    [ -f "$f" ] || continue
    case $f in *.pending|*/README.md) continue ;; esac
    [ "$(stat -c %s "$f")" -le 65536 ] && cp "$f" "$corpus/seed-$(basename "$f")"
  done
}

run_one() {  # PARSER: fuzz it; status in $work/logs/PARSER.rc
  local p=$1 bin=$build/tests/fuzz/fuzz_$1 log=$work/logs/$1.log tmp=$work/tmp/$1
  mkdir -p "$tmp"
  # Leaks are findings too (the parsers keep nothing between inputs); third-party ones: lsan.supp.
  TMPDIR=$tmp \
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1} \
  LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/tests/fuzz/lsan.supp:print_suppressions=0} \
  UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
    "$bin" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 ${FUZZ_SEED:+-seed=$FUZZ_SEED} ${FUZZ_RUNS:+-runs=$FUZZ_RUNS} \
           -artifact_prefix="$work/artifacts/$p/" "$work/corpus/$p" >"$log" 2>&1
  echo $? >"$work/logs/$p.rc"
  rm -rf "$tmp"
}

for p in "${parsers[@]}"; do
  [ -x "$build/tests/fuzz/fuzz_$p" ] || { echo "fuzz: $build/tests/fuzz/fuzz_$p is not built" >&2; exit 2; }
  prepare "$p"
  rm -f "$work/logs/$p.rc"
done
echo "fuzz: ${#parsers[@]} targets x ${seconds} s, $jobs at a time (corpora in $work/corpus)"
for p in "${parsers[@]}"; do
  run_one "$p" &
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n; done
done
wait

failed=0
for p in "${parsers[@]}"; do
  rc=$(cat "$work/logs/$p.rc" 2>/dev/null || echo "?")
  log=$work/logs/$p.log
  stats=$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}')
  corpus=$(ls "$work/corpus/$p" | wc -l)
  if [ "$rc" = 0 ]; then
    echo "fuzz_$p: ok, ${stats:-?} inputs, corpus $corpus"
  else
    failed=1
    echo "fuzz_$p: FINDING (exit $rc) after ${stats:-?} inputs; log $log"
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error:|terminate called|  what\(\)|fuzz_[a-z_]+: )' "$log" | head -8
    grep -E 'Test unit written to|^artifact_prefix' "$log" | sed 's/^/  /'
    grep -E '^ +#[0-9]+ ' "$log" | grep -v -E 'libFuzzer|fuzzer::|__asan|__ubsan|__sanitizer|libc\.so|_start' | head -8
  fi
done
[ $failed = 0 ] || echo "fuzz: replay with $build/tests/fuzz/fuzz_PARSER ARTIFACT; keep it as tests/fuzz/regressions/PARSER/NAME"
exit $failed

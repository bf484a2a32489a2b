#!/usr/bin/env bash
# Interleaved A/B of two versions of the builders in one process: side A is builders/ at a git
# revision, side B the working tree's builders/. Each side's builders/*.cpp are compiled with the
# build's flags under their own namespace (-Dbvhlab=bvhlabA, bvhlabB) and linked into one program
# with the main libraries (datasets, layout: the inputs), which then builds one mesh with both
# versions in alternating order and prints the paired ratio B / A with its 95% interval and whether
# the trees are bit for bit the same.
#
# Why: a build's time moves by several percent from process to process (heap, huge pages granted,
# code placement), more than most single speed changes to a builder; two binaries run one after the
# other cannot resolve 1-3%, two versions interleaved in one process can. Run the script once with
# REV = HEAD on a clean tree (A/A): that gives the placement bias of the two sides (B ran 0.5-0.7%
# slower than A in such runs on this machine, 4 December 2026).
#
#   bash experiments/bench/ab_revisions.sh REV [main.cpp options: --builder B --mesh PATH|large1M --heap warm|cold|adaptive (warm by default)
#        --rounds N --threads T --wall --bins K --ploc-radius R --ploc-top-down F --leaf-size L]
#   AB_KEEP=/tmp/ab bash experiments/bench/ab_revisions.sh REV ...   (keeps the program for more runs)
#
# Needs a configured and built `build/` (bash setup.sh build): its libraries and compile flags.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
rev="${1:?usage: ab_revisions.sh REV [options]}"
shift
build="$root/build"
[[ -f "$build/libbvhlab_builders.a" ]] || { echo "ab_revisions: no $build/libbvhlab_builders.a (bash setup.sh build first)" >&2; exit 2; }
git -C "$root" rev-parse --verify --quiet "$rev^{commit}" >/dev/null || { echo "ab_revisions: '$rev' is not a revision of $root" >&2; exit 2; }

work="$(mktemp -d /tmp/bvhlab-ab.XXXXXX)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/A" "$work/B"
git -C "$root" archive "$rev" builders | tar -x -C "$work/A"
cp -r "$root/builders" "$work/B/"

# The flags CMake compiles the builders with (Release: -O3 -DNDEBUG), as compile_commands.json has them.
flags="$(python3 - "$build/compile_commands.json" <<'PY'
import json, shlex, sys
for entry in json.load(open(sys.argv[1])):
    if entry["file"].endswith("builders/sah_binned.cpp"):
        args = shlex.split(entry["command"])
        print(" ".join(a for a in args[1:] if a.startswith(("-O", "-D", "-std", "-f", "-m")) and a != "-c"))
        break
PY
)"
cxx="${CXX:-c++}"
pids=()
for side in A B; do
  mkdir -p "$work/obj$side"
  for src in "$work/$side"/builders/*.cpp "$root/experiments/bench/ab/variant.cpp"; do
    # The side's own headers first: builders/*.hpp may differ between A and B.
    $cxx $flags -Dbvhlab=bvhlab$side -DAB_SIDE=abBuild$side -I"$work/$side" -I"$root" \
      -c "$src" -o "$work/obj$side/$(basename "$src" .cpp).o" &
    pids+=($!)
    if (( ${#pids[@]} >= $(nproc) )); then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
  done
done
for p in "${pids[@]}"; do wait "$p"; done
# Link line: the main libraries the app links (their order matters: static libraries, users first).
$cxx $flags -DBVHLAB_SOURCE_DIR="\"$root\"" -I"$root" "$root/experiments/bench/ab/main.cpp" "$work"/objA/*.o "$work"/objB/*.o \
  -o "$work/ab" -L"$build" -lbvhlab_layout -lbvhlab_builders -lbvhlab_datasets -lembree3 -ltbb -lassimp \
  -lOpenMeshCore -lOpenImageIO -lOpenImageIO_Util -lpugixml -lpthread
# AB_KEEP=PATH keeps the program there, for more runs of the same pair (it takes main.cpp's options).
if [[ -n "${AB_KEEP:-}" ]]; then cp "$work/ab" "$AB_KEEP"; fi
echo "ab_revisions: A = $rev ($(git -C "$root" rev-parse --short "$rev")), B = the working tree" >&2
"$work/ab" "$@"

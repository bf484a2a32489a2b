#!/bin/bash
# experiments/remote/bundle.py: the bundled bvhlab loads nothing from outside its lib/ but the C/C++
# runtime, and renders the report scene (an EXR world read through the bundled OpenImageIO, whose
# unused codecs are stubs) through EGL to the same PNG, byte for byte, as the installed build.
# Usage: remote_bundle.sh BVHLAB_BINARY SOURCE_DIR
set -u
bin=$1; src=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "remote_bundle: FAIL: $*"; exit 1; }
python3 "$src/experiments/remote/bundle.py" --binary "$bin" --out "$tmp/b" || fail "bundle.py exited $?"
[ -x "$tmp/b/bvhlab" ] || fail "no bvhlab in the bundle"
n=$(ls "$tmp/b/lib" | wc -l); [ "$n" -ge 20 ] || fail "only $n libraries bundled"
outside=$(LD_LIBRARY_PATH="$tmp/b/lib" ldd "$tmp/b/bvhlab" | grep "=>" | grep -v "$tmp/b/lib/" |
          grep -Ev '/(libc|libm|libstdc\+\+|libgcc_s|libdl|libpthread|librt|libresolv|libutil)\.so')
[ -z "$outside" ] || fail "loaded from outside the bundle: $outside"
grep -q "not found" <(LD_LIBRARY_PATH="$tmp/b/lib" ldd "$tmp/b/bvhlab") && fail "unresolved library"
stub="$tmp/b/lib/libOSMesa.so.8"
[ -f "$stub" ] || fail "libOSMesa.so.8 was not stubbed"
readelf -d "$stub" | grep -q NEEDED && fail "the OSMesa stub has dependencies"
[ "$(stat -c %s "$stub")" -lt 100000 ] || fail "the OSMesa stub is not a stub"
args=(render "$src/datasets/scenes/report.toml" --backend egl --width 96 --height 54 --frames 1 --warmup 0)
"$bin" "${args[@]}" -o "$tmp/installed.png" >/dev/null 2>&1 || fail "installed render failed"
LD_LIBRARY_PATH="$tmp/b/lib" "$tmp/b/bvhlab" "${args[@]}" -o "$tmp/bundled.png" >/dev/null 2>"$tmp/err" ||
  fail "bundled render failed: $(tail -3 "$tmp/err")"
cmp -s "$tmp/installed.png" "$tmp/bundled.png" || fail "bundled and installed renders differ"
echo "remote_bundle: ok ($n libraries in lib/)"

#!/bin/bash
# Every builder over three meshes with `bvhlab build --json` (tree statistics only; no GL), and every
# layout and triangle format over one tree. Writes build.jsonl and layout-bytes.jsonl
# into this folder. Run from the repository root:
#   bash docs/results/builders-quality/make.sh        (BVHLAB=PATH to use another build of bvhlab)
set -eu
B=${BVHLAB:-./build/bvhlab}   # the binary (BVHLAB=... to use another build)
out=docs/results/builders-quality/build.jsonl
: > "$out"
for mesh in datasets/cache/meshes/bunny00.off datasets/scenes/bench/ship.toml datasets/scenes/bench/interior.toml; do
  for b in sah-binned median sah-sweep sbvh lbvh ploc hploc embree embree-low; do
    "$B" build --mesh "$mesh" --builder "$b" --json | python3 -c \
      'import json,sys; d=json.load(sys.stdin); d["input"]=sys.argv[1]; print(json.dumps(d, sort_keys=True))' "$mesh" >> "$out"
  done
done
# Every layout and triangle format over sah-binned's bunny tree: memory per triangle (layout-bytes.jsonl).
out=docs/results/builders-quality/layout-bytes.jsonl
: > "$out"
for layout in v1 bvh2-cb bvh4 bvh8 cwbvh; do
  for tri in raw precomputed indexed; do
    "$B" build --mesh datasets/cache/meshes/bunny00.off --layout "$layout" --triangles "$tri" --json | python3 -c \
      'import json,sys; d=json.load(sys.stdin); d["input"]=sys.argv[1]; print(json.dumps(d, sort_keys=True))' \
      datasets/cache/meshes/bunny00.off >> "$out"
  done
done

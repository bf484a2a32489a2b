#!/usr/bin/env bash
# Fetch bvhlab's external data from Debian packages without installing them:
#   libcgal-demo  -> usr/share/doc/libcgal-dev/data.tar.gz -> data/meshes/*  -> datasets/cache/meshes/
#   blender-data  -> usr/share/blender/datafiles/studiolights/world/*       -> datasets/cache/worlds/
#   flightgear-data-models -> .../Maritime/Military/CG-57-high-detail/*     -> datasets/cache/meshes/
# Every kept file is listed with its sha256 in datasets/checksums.sha256 (paths relative to the cache).
# A complete, verified cache makes this a no-op; a checksum mismatch is an error (delete the file and rerun).
# Needs only apt-get (after `apt-get update`), dpkg-deb, tar, gzip and sha256sum. Prints one line per action.
#   bash datasets/fetch.sh            fetch what is missing, verify everything
#   bash datasets/fetch.sh --verify   verify the cache only, never download
set -euo pipefail

HERE="$(cd "$(dirname "$0")" && pwd)"
CACHE="${BVHLAB_DATA_CACHE:-$HERE/cache}"
SUMS="$HERE/checksums.sha256"

# What we keep. Meshes: the report's bunny, a few classic scanned models (10k-89k triangles), and one
# binary STL and two small ASCII PLYs (one with normals and extra elements) so the loaders see real
# files of every format.
MESHES=(bunny00.off armadillo.off ChineseDragon-10kv.off refined_elephant.off cow.off knot1.off pig.stl sphere.ply
        colored_tetra.ply)
WORLDS=(city.exr courtyard.exr forest.exr interior.exr night.exr studio.exr sunrise.exr sunset.exr license.txt)
# A real model of >= 150k triangles for the bench suite (datasets/scenes/bench/ship.toml): the cruiser
# CG-57 from FlightGear's models (GPL; AC3D text, 86,379 surfaces, ~180k triangles once its quads are
# split) and the six textures it references (2.6 MB). The package is a 144 MB download (4 s on this
# project's machine, plus ~17 s to extract the one folder).
FG_MODEL=(CG-57.ac CG-57-texture.png RSD-rails.png deck-gray-large.png deck-gray.png deck-white.png nets.png)
FG_DIR=usr/share/games/flightgear/Models/Maritime/Military/CG-57-high-detail
CGAL_TARBALL=usr/share/doc/libcgal-dev/data.tar.gz
BLENDER_WORLDS=usr/share/blender/datafiles/studiolights/world

say() { echo "fetch: $*"; }
die() { echo "fetch: error: $*" >&2; exit 1; }

[ -f "$SUMS" ] || die "$SUMS is missing"
for tool in sha256sum tar dpkg-deb; do
  command -v "$tool" >/dev/null || die "'$tool' not found"
done

# Files in the checksum list, relative to the cache.
mapfile -t LISTED < <(awk 'NF == 2 { print $2 }' "$SUMS")
for f in "${MESHES[@]/#/meshes/}" "${FG_MODEL[@]/#/meshes/}" "${WORLDS[@]/#/worlds/}"; do
  grep -qxF "$f" < <(printf '%s\n' "${LISTED[@]}") || die "$f has no entry in $SUMS"
done

expected_sum() { awk -v f="$1" '$2 == f { print $1 }' "$SUMS"; }

# verify_file ROOT RELPATH -> 0 ok, 1 mismatch (prints both sums)
verify_file() {
  local want got
  want="$(expected_sum "$2")"
  got="$(sha256sum "$1/$2" | awk '{ print $1 }')"
  if [ "$want" != "$got" ]; then
    echo "fetch: error: checksum mismatch for $1/$2: expected $want, got $got" >&2
    return 1
  fi
}

missing=()
bad=0
for f in "${LISTED[@]}"; do
  if [ -f "$CACHE/$f" ]; then
    verify_file "$CACHE" "$f" || bad=1
  else
    missing+=("$f")
  fi
done
[ "$bad" -eq 0 ] || die "cached data does not match $SUMS (delete the file(s) named above and rerun)"

if [ ${#missing[@]} -eq 0 ]; then
  say "cache complete: ${#LISTED[@]} files in $CACHE verified, nothing to do"
  exit 0
fi
if [ "${1:-}" = "--verify" ]; then
  die "${#missing[@]} file(s) missing from $CACHE (first: ${missing[0]}); run: bash datasets/fetch.sh"
fi

is_fg_file() { local x; for x in "${FG_MODEL[@]}"; do [ "meshes/$x" = "$1" ] && return 0; done; return 1; }
need_meshes=0 need_worlds=0 need_fg=0
for f in "${missing[@]}"; do
  case "$f" in
    meshes/*) if is_fg_file "$f"; then need_fg=1; else need_meshes=1; fi ;;
    worlds/*) need_worlds=1 ;;
    *) die "don't know which package provides $f" ;;
  esac
done

WORK="$(mktemp -d "${TMPDIR:-/tmp}/bvhlab-fetch.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
# apt-get download drops to user _apt when run as root; let it write here (avoids a sandbox warning).
chmod 755 "$WORK"
if [ "$(id -u)" -eq 0 ] && id _apt >/dev/null 2>&1; then chown _apt "$WORK"; fi

DEB=""
download() {  # download PACKAGE -> sets DEB to the path of the .deb
  say "downloading Debian package $1 (not installing it)"
  (cd "$WORK" && apt-get download -q=2 "$1" >/dev/null) ||
    die "apt-get download $1 failed (run 'apt-get update' first; needs Debian's archive)"
  DEB="$(ls "$WORK"/"$1"_*.deb 2>/dev/null | head -n 1)"
  [ -n "$DEB" ] || die "apt-get download $1 produced no .deb"
}

STAGE="$WORK/stage"
mkdir -p "$STAGE/meshes" "$STAGE/worlds"

if [ "$need_meshes" -eq 1 ]; then
  download libcgal-demo
  say "extracting $CGAL_TARBALL from $(basename "$DEB")"
  dpkg-deb --fsys-tarfile "$DEB" | tar -x -C "$WORK" "./$CGAL_TARBALL" ||
    die "$(basename "$DEB") has no $CGAL_TARBALL"
  say "extracting ${#MESHES[@]} meshes from data.tar.gz"
  tar -xzf "$WORK/$CGAL_TARBALL" -C "$WORK" "${MESHES[@]/#/data/meshes/}" ||
    die "data.tar.gz lacks some of: ${MESHES[*]}"
  for m in "${MESHES[@]}"; do mv "$WORK/data/meshes/$m" "$STAGE/meshes/$m"; done
fi

if [ "$need_worlds" -eq 1 ]; then
  download blender-data
  say "extracting ${#WORLDS[@]} world files from $(basename "$DEB")"
  dpkg-deb --fsys-tarfile "$DEB" | tar -x -C "$WORK" "${WORLDS[@]/#/./$BLENDER_WORLDS/}" ||
    die "$(basename "$DEB") lacks some of: ${WORLDS[*]}"
  for w in "${WORLDS[@]}"; do mv "$WORK/$BLENDER_WORLDS/$w" "$STAGE/worlds/$w"; done
fi

if [ "$need_fg" -eq 1 ]; then
  download flightgear-data-models
  say "extracting ${#FG_MODEL[@]} files of $FG_DIR from $(basename "$DEB")"
  dpkg-deb --fsys-tarfile "$DEB" | tar -x -C "$WORK" "${FG_MODEL[@]/#/./$FG_DIR/}" ||
    die "$(basename "$DEB") lacks some of: ${FG_MODEL[*]}"
  for m in "${FG_MODEL[@]}"; do mv "$WORK/$FG_DIR/$m" "$STAGE/meshes/$m"; done
  rm -f "$DEB"  # 144 MB: free the space before copying into the cache
fi

# Verify everything that was extracted before anything enters the cache.
for f in "${missing[@]}"; do
  [ -f "$STAGE/$f" ] || die "$f was not extracted"
  verify_file "$STAGE" "$f" || die "extracted data does not match $SUMS (a different package version?)"
done
for f in "${missing[@]}"; do
  mkdir -p "$(dirname "$CACHE/$f")"
  # Copy next to the target, then rename: an interrupted run never leaves a partial file in the cache.
  cp "$STAGE/$f" "$CACHE/$f.partial"
  mv -f "$CACHE/$f.partial" "$CACHE/$f"
  say "stored $f ($(stat -c %s "$CACHE/$f") bytes, sha256 ok)"
done
say "done: ${#missing[@]} file(s) added, ${#LISTED[@]} files in $CACHE verified"

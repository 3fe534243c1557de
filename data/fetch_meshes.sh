#!/usr/bin/env bash
# Fetches the real meshes (DESIGN §8) from Debian's libcgal-demo package into data/real/
# (ignored by git). Idempotent: does nothing when they are already there.
# Usage: data/fetch_meshes.sh [DEST]     exit 0 on success, 3 when the package is unreachable.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
dest=${1:-$here/real}
meshes=(dino elephant knot1 armadillo bunny00 triceratops homer fandisk camel cow bull ChineseDragon-10kv)
if [ -f "$dest/.complete" ]; then exit 0; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
if ! apt-get download libcgal-demo >/dev/null 2>&1; then
  # apt's lists may be stale on a fresh machine; refresh once (needs root) and retry.
  if [ "$(id -u)" = 0 ]; then apt-get update -qq >/dev/null 2>&1 || true; fi
  if ! apt-get download libcgal-demo >/dev/null 2>&1; then
    echo "fetch_meshes: cannot download Debian's libcgal-demo package (offline?)" >&2
    exit 3
  fi
fi
dpkg-deb -x libcgal-demo_*.deb pkg
tarball=pkg/usr/share/doc/libcgal-dev/data.tar.gz
members=()
for m in "${meshes[@]}"; do members+=("data/meshes/$m.off"); done
tar -xzf "$tarball" "${members[@]}"
mkdir -p "$dest"
for m in "${meshes[@]}"; do mv "data/meshes/$m.off" "$dest/$m.off"; done
touch "$dest/.complete"
echo "fetch_meshes: ${#meshes[@]} meshes in $dest"

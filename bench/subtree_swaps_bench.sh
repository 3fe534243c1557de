#!/bin/bash
# Subtree swaps as a build step (docs/BENCHMARKS.md, "Subtree swaps as a build step"): for each
# mesh, the default build and the same with --subtree-swaps at DEPTH, one after the other, each
# timed and certified; prints each build's wall time, the swaps' own line, and the exact e.
#
# Usage: bench/subtree_swaps_bench.sh VOBB OUTDIR DEPTH MESH...   (run from the repository root;
# MESH names data/real/MESH.off)
set -euo pipefail
vobb=$1 out=$2 depth=$3
shift 3
mkdir -p "$out"
for mesh in "$@"; do
  off=data/real/$mesh.off
  for variant in default swaps; do
    flag=()
    [ "$variant" = swaps ] && flag=(--subtree-swaps)
    tree="$out/${mesh}_${variant}_$depth.json"
    /usr/bin/time -f "$mesh $variant depth $depth: %e s wall, %U s user, %M KB" -o "$out/time.txt" \
      "$vobb" build "$off" -o "$tree" --depth "$depth" "${flag[@]}" 2> "$out/${mesh}_${variant}_$depth.log"
    cat "$out/time.txt"
    grep "subtree swaps" "$out/${mesh}_${variant}_$depth.log" || true
    "$vobb" certify "$off" "$tree" --json --quiet > "${tree%.json}.cert.json"
    python3 -c 'import json, sys; print(sys.argv[2], "e", json.load(open(sys.argv[1]))["weighted_error"])' \
      "${tree%.json}.cert.json" "$mesh $variant"
  done
done

#!/bin/bash
# The overlap-aware objective's benchmark (docs/BENCHMARKS.md, "Overlap-aware objective"): for
# each mesh, the OBB-Tree baseline and the variational tree under --objective obv and omv at
# DEPTH, each build timed, each tree certified; prints e and each layer's exact OMV.
#
# Usage: bench/objective_bench.sh VOBB OUTDIR DEPTH MESH...   (run from the repository root;
# MESH names data/real/MESH.off)
set -euo pipefail
vobb=$1 out=$2 depth=$3
shift 3
mkdir -p "$out"
for mesh in "$@"; do
  off=data/real/$mesh.off
  "$vobb" build "$off" -o "$out/${mesh}_obbtree_$depth.json" --method obbtree --depth "$depth" --quiet
  for objective in obv omv; do
    /usr/bin/time -f "$mesh $objective depth $depth: %e s wall, %U s user, %M KB" -a -o "$out/build_times.txt" \
      "$vobb" build "$off" -o "$out/${mesh}_${objective}_$depth.json" --depth "$depth" --objective "$objective" --quiet
  done
  for tree in obbtree obv omv; do
    "$vobb" certify "$off" "$out/${mesh}_${tree}_$depth.json" --json --quiet > "$out/${mesh}_${tree}_$depth.cert.json"
    python3 - "$out/${mesh}_${tree}_$depth.cert.json" "$mesh" "$tree" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
print(sys.argv[2], sys.argv[3], "e", repr(c["weighted_error"]), [l["omv"] for l in c["levels"]])
PY
  done
done
cat "$out/build_times.txt"

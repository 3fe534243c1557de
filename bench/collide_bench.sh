#!/bin/bash
# The collision benchmark of docs/BENCHMARKS.md (issue 7): for dino, elephant and knot1 at
# depths 8 and 12, builds the baseline and the variational tree (`--objective obv`, the paper's),
# then runs `vobb collide` in the dynamic scene (1,000 colliders, 10 s) and the static one
# (5,000 poses) for seeds 1..SEEDS, and prints the summary table (bench/collide_summary.py).
#
# Usage: bench/collide_bench.sh VOBB OUTDIR [SEEDS [MARGIN]]   (run from the repository root)
# With MARGIN (> 0), a third tree joins every run: the variational build with --collider-margin
# set to MARGIN times the mesh's bounding-box half diagonal (X_marginMARGIN_D.json); such runs
# are named run_X_D_MODE_sS_marginMARGIN.json, apart from the two-tree runs.
# Trees and runs already in OUTDIR are kept, so an interrupted run can be started again.
# DEPTHS and MESHES (environment) narrow the set, e.g. to run two meshes side by side.
set -euo pipefail
# shellcheck source=bench/collide_runs.sh
. "$(dirname "$0")/collide_runs.sh"
vobb=$1 out=$2 seeds=${3:-5} margin=${4:-}
mkdir -p "$out"
if [ -n "$margin" ]; then
  python3 -c "import math, sys; m = float(sys.argv[1]); sys.exit(0 if math.isfinite(m) and m > 0 else 1)" "$margin" ||
    { echo "collide_bench.sh: MARGIN must be a number > 0, not '$margin'" >&2; exit 2; }
fi
for depth in ${DEPTHS:-8 12}; do
  for mesh in ${MESHES:-dino elephant knot1}; do
    off=data/real/$mesh.off
    trees=()
    for method in obbtree variational ${margin:+margin$margin}; do
      tree=$out/${mesh}_${method}_$depth.json
      trees+=("$tree")
      [ -s "$tree" ] && continue
      if [ "$method" = "margin$margin" ]; then
        length=$("$vobb" info "$off" --json | python3 -c "import json, math, sys
b = json.load(sys.stdin)['bbox']
print(repr($margin * 0.5 * math.dist(b['min'], b['max'])))")
        echo "$mesh: collider margin $length" >> "$out/build_times.txt"
        args=(--method variational --objective obv --collider-margin "$length")
      elif [ "$method" = variational ]; then
        args=(--method variational --objective obv)  # the paper's objective, as recorded
      else
        args=(--method "$method")
      fi
      /usr/bin/time -f "$mesh $method depth $depth: %e s wall, %U s user" -a -o "$out/build_times.txt" \
        "$vobb" build "$off" -o "$tree" "${args[@]}" --depth "$depth" --backend cpu --quiet
    done
    collide_runs "$vobb" "$off" "$out" "$mesh" "$depth" "$seeds" "${margin:+_margin$margin}" "${trees[@]}"
  done
done
python3 "$(dirname "$0")/collide_summary.py" "$out"/run_*.json

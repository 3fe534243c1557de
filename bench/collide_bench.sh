#!/bin/bash
# The collision benchmark of docs/BENCHMARKS.md (issue 7): for dino, elephant and knot1 at
# depths 8 and 12, builds the baseline and the variational tree, then runs `vobb collide` in
# the dynamic scene (1,000 colliders, 10 s) and the static one (5,000 poses) for seeds 1..SEEDS,
# and prints the summary table (bench/collide_summary.py).
#
# Usage: bench/collide_bench.sh VOBB OUTDIR [SEEDS]   (run from the repository root)
# Trees and runs already in OUTDIR are kept, so an interrupted run can be started again.
set -euo pipefail
vobb=$1 out=$2 seeds=${3:-5}
mkdir -p "$out"
for depth in 8 12; do
  for mesh in dino elephant knot1; do
    off=data/real/$mesh.off
    for method in obbtree variational; do
      tree=$out/${mesh}_${method}_$depth.json
      [ -s "$tree" ] || /usr/bin/time -f "$mesh $method depth $depth: %e s wall, %U s user" -a -o "$out/build_times.txt" \
        "$vobb" build "$off" -o "$tree" --method "$method" --depth "$depth" --backend cpu --quiet
    done
    for seed in $(seq 1 "$seeds"); do
      for mode in dynamic static; do
        run=$out/run_${mesh}_${depth}_${mode}_s$seed.json
        [ -s "$run" ] && continue
        if [ "$mode" = dynamic ]; then args="--colliders 1000 --seconds 10"; else args="--static --colliders 5000"; fi
        # shellcheck disable=SC2086
        "$vobb" collide "$off" "$out/${mesh}_obbtree_$depth.json" "$out/${mesh}_variational_$depth.json" \
          $args --seed "$seed" --json -o "$run"
      done
    done
  done
done
python3 "$(dirname "$0")/collide_summary.py" "$out"/run_*.json

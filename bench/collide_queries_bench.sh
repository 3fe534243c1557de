#!/bin/bash
# The collision benchmark with the recorded-query objective (docs/BENCHMARKS.md, issue 7): for
# dino, elephant and knot1 at depths 8 and 12, builds the baseline, records the dynamic scene's
# queries against it with training seeds (never the reported ones), builds the variational
# tree on those recorded hits (`vobb build --queries`), then runs `vobb collide` with both
# trees (and the paper-objective tree where OUTDIR holds one, X_variational_D.json) in the
# dynamic scene (1,000 colliders, 10 s) and the static one (5,000 poses) for seeds 1..SEEDS,
# and prints the summary table (bench/collide_summary.py).
#
# Usage: bench/collide_queries_bench.sh VOBB OUTDIR [SEEDS [EVERY]]   (from the repository root)
# EVERY: record every EVERY-th query (default 2). TRAIN_SEEDS (environment, default "101 102")
# are the recording's seeds; DEPTHS and MESHES narrow the set. Files already in OUTDIR are
# kept, so an interrupted run can be started again.
set -euo pipefail
# shellcheck source=bench/collide_runs.sh
. "$(dirname "$0")/collide_runs.sh"
vobb=$1 out=$2 seeds=${3:-5} every=${4:-2}
train=${TRAIN_SEEDS:-101 102}
[ -n "${train// /}" ] || { echo "collide_queries_bench.sh: TRAIN_SEEDS names no seed" >&2; exit 2; }
mkdir -p "$out"
for s in $(seq 1 "$seeds"); do
  for t in $train; do
    [ "$s" != "$t" ] || { echo "collide_queries_bench.sh: training seed $t is also a reported seed" >&2; exit 2; }
  done
done
for depth in ${DEPTHS:-8 12}; do
  for mesh in ${MESHES:-dino elephant knot1}; do
    off=data/real/$mesh.off
    base=$out/${mesh}_obbtree_$depth.json
    [ -s "$base" ] || "$vobb" build "$off" -o "$base" --method obbtree --depth "$depth" --quiet
    queries=()
    for t in $train; do
      q=$out/queries_${mesh}_${depth}_s$t.json
      [ -s "$q" ] || "$vobb" collide "$off" "$base" --colliders 1000 --seconds 10 --seed "$t" --no-fcl \
        --json -o /dev/null --record-queries "$q" --record-every "$every"
      queries+=(--queries "$q")
    done
    tree=$out/${mesh}_queries_$depth.json
    [ -s "$tree" ] || /usr/bin/time -f "$mesh queries depth $depth: %e s wall, %U s user" -a -o "$out/build_times.txt" \
      "$vobb" build "$off" -o "$tree" "${queries[@]}" --depth "$depth" --quiet
    trees=("$base" "$tree")
    [ ! -s "$out/${mesh}_variational_$depth.json" ] || trees+=("$out/${mesh}_variational_$depth.json")
    collide_runs "$vobb" "$off" "$out" "$mesh" "$depth" "$seeds" _queries "${trees[@]}"
  done
done
python3 "$(dirname "$0")/collide_summary.py" "$out"/run_*_queries.json

#!/bin/bash
# Variational builds (CPU twin) against the thread count, and against an earlier vobb on the
# same machine: where the nodes of a level are searched at once, a build should scale with the
# cores beyond what the estimator's batches (6 to 33 boxes) allow. Every pair of old and new
# builds runs back to back, alternating which goes first, so the ratios compare like with
# like; every tree is compared with `cmp` against the first one of its kind.
#
# Usage: bench/build_threads.sh NEW_VOBB OUT_DIR [OLD_VOBB] [MESHES] [DEPTHS] [THREADS]
#   NEW_VOBB  the vobb binary under test
#   OUT_DIR   where the trees and logs go
#   OLD_VOBB  optional: an earlier vobb, run alternately with the new one at every thread count
#   MESHES    default "dino elephant knot1" (data/real/NAME.off; data/fetch_meshes.sh)
#   DEPTHS    default "8"
#   THREADS   default: "2 4 8 16", capped at nproc
set -u
NEW=${1:?NEW_VOBB}
O=${2:?OUT_DIR}
OLD=${3:-}
MESHES=${4:-"dino elephant knot1"}
DEPTHS=${5:-8}
THREADS=${6:-"2 4 8 16"}
mkdir -p "$O"
echo "== machine: $(date -u), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)"

run() {  # run LABEL BINARY MESH DEPTH THREADS: prints LABEL seconds
  local label=$1 bin=$2 mesh=$3 depth=$4 t=$5 tree t0 t1
  tree="$O/$mesh-d$depth-$label-t$t.json"
  t0=$(date +%s.%N)
  if ! "$bin" build "data/real/$mesh.off" -o "$tree" --depth "$depth" --backend cpu --quiet --threads "$t" \
      >"$tree.log" 2>&1; then
    echo "FAILED: $label $mesh depth $depth threads $t"; cat "$tree.log"; return 1
  fi
  t1=$(date +%s.%N)
  python3 -c "import sys; print(f'{sys.argv[1]:4s} {sys.argv[2]:9s} depth {sys.argv[3]:>2s} threads {sys.argv[4]:>2s}: {float(sys.argv[6]) - float(sys.argv[5]):7.2f} s')" \
    "$label" "$mesh" "$depth" "$t" "$t0" "$t1"
  local first="$O/$mesh-d$depth-first.json"
  if [ -e "$first" ]; then
    cmp -s "$first" "$tree" || echo "DIFFERENT TREE: $tree"
  else
    cp "$tree" "$first"
  fi
}

n=0
for mesh in $MESHES; do
  for depth in $DEPTHS; do
    for t in $THREADS; do
      [ "$t" -gt "$(nproc)" ] && continue
      if [ -n "$OLD" ] && [ $((n % 2)) -eq 1 ]; then
        run old "$OLD" "$mesh" "$depth" "$t"; run new "$NEW" "$mesh" "$depth" "$t"
      elif [ -n "$OLD" ]; then
        run new "$NEW" "$mesh" "$depth" "$t"; run old "$OLD" "$mesh" "$depth" "$t"
      else
        run new "$NEW" "$mesh" "$depth" "$t"
      fi
      n=$((n + 1))
    done
  done
done

#!/bin/bash
# What the final refit costs with each backend: `vobb build` with and without `--no-refit`,
# alternated, on the GL estimator and on the CPU twin, at two depths; whether the GL and
# CPU-twin trees are the same bytes. The refit asks for a few boxes at a time, node by node,
# so a backend with a fixed cost per call (GL: a draw, a read-back) pays it once a node.
#
# Usage: bench/refit_gl_bench.sh VOBB OUT_DIR [MESH] [SHALLOW] [DEEP] [ROUNDS]
#   VOBB      the vobb binary
#   OUT_DIR   where the trees go
#   MESH      a name under data/real (default dino)
#   SHALLOW   the first depth (default 8)
#   DEEP      the second depth (default 12)
#   ROUNDS    rounds of the alternation at DEEP with GL (default 2; one round elsewhere)
set -u
V=${1:?VOBB}
O=${2:?OUT_DIR}
MESH=${3:-dino}
D1=${4:-8}
D2=${5:-12}
ROUNDS=${6:-2}
mkdir -p "$O"

build() {  # build LABEL DEPTH ARGS...: one `vobb build`, timed (wall, user, peak memory)
  local label=$1 depth=$2
  shift 2
  /usr/bin/time -f "[$label: %e s wall, %U s user, %M KB, rc %x]" \
    "$V" build "data/real/$MESH.off" -o "$O/$label.json" --depth "$depth" --quiet "$@"
}

echo "== machine: $(date -u), $(nproc) cores"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null || echo "no nvidia-smi"

for r in $(seq 1 "$ROUNDS"); do
  build "gl$D2-refit-r$r" "$D2" --backend gl
  build "gl$D2-norefit-r$r" "$D2" --backend gl --no-refit
done
build "cpu$D2-refit" "$D2" --backend cpu
build "cpu$D2-norefit" "$D2" --backend cpu --no-refit
build "gl$D1-refit" "$D1" --backend gl
build "gl$D1-norefit" "$D1" --backend gl --no-refit
build "cpu$D1-refit" "$D1" --backend cpu
build "cpu$D1-norefit" "$D1" --backend cpu --no-refit

for d in "$D1" "$D2"; do
  for v in refit norefit; do
    gl="$O/gl$d-$v.json"
    [ -e "$gl" ] || gl="$O/gl$d-$v-r1.json"
    if cmp -s "$gl" "$O/cpu$d-$v.json"; then
      echo "depth $d, $v: the GL and CPU-twin trees are the same bytes"
    else
      echo "depth $d, $v: the GL and CPU-twin trees differ"
    fi
  done
done

#!/bin/bash
# The GL estimator on a GPU (issue 4's benchmark, run where a GPU is lent): the GL tests on that
# driver, per-OBV times of GL against the CPU twin on the same machine's cores at several m, and
# variational builds with each backend. Everything runs in this one process tree, one after the
# other, so the ratios compare like with like.
#
# Usage: bench/gpu_bench.sh BUILD_DIR OUT_DIR [OLD_DIR]
#   BUILD_DIR  a Release build of this checkout (bench/, app/ and tests/ are used)
#   OUT_DIR    where the logs and trees go
#   OLD_DIR    optional: vobb and vobb-bench-estimator of an earlier commit, run alternately
#              with the new ones on the same inputs (the before/after ratios)
# Needs data/real (data/fetch_meshes.sh) and an EGL that reaches the GPU.
set -u
B=${1:?BUILD_DIR}
O=${2:?OUT_DIR}
OLD=${3:-}
mkdir -p "$O"
stamp() { date +%s.%N; }
timed() {  # timed LABEL COMMAND...: runs it, prints its wall seconds
  local label=$1 t0 rc
  shift
  t0=$(stamp)
  "$@"
  rc=$?
  python3 -c "import sys; print(f'[{sys.argv[1]}: {float(sys.argv[3]) - float(sys.argv[2]):.2f} s wall, rc {sys.argv[4]}]')" \
    "$label" "$t0" "$(stamp)" "$rc"
}

echo "== machine"
date -u
nproc
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "no nvidia-smi"

echo "== the GL tests on this driver"
timed fast_gl_tests "$B/tests/fast_gl_tests" >"$O/fast_gl_tests.log" 2>&1
tail -1 "$O/fast_gl_tests.log"
grep -E "FAILED|renderer" "$O/fast_gl_tests.log" | head
if [ -x "$B/tests/validate_tests" ]; then
  timed estimator_accuracy "$B/tests/validate_tests" --gtest_filter='EstimatorAccuracy.*' >"$O/estimator_accuracy.log" 2>&1
  tail -1 "$O/estimator_accuracy.log"
fi

echo "== per-OBV times, m = 32 (the llvmpipe table's command)"
for mesh in dino knot1; do
  for round in 1 2; do
    [ -n "$OLD" ] && { echo "-- old, $mesh, round $round"; "$OLD/vobb-bench-estimator" data/real/$mesh.off --m 32 --leaves 1000 --roots 100 --ablation-boxes 100; }
    echo "-- new, $mesh, round $round"
    "$B/bench/vobb-bench-estimator" data/real/$mesh.off --m 32 --leaves 1000 --roots 100 --ablation-boxes 100
  done
done

echo "== per-OBV times against m (dino; fewer boxes at large m, where the CPU twin's one-thread row is slow)"
for spec in "128 500 50" "512 100 20" "2048 20 5"; do
  set -- $spec
  "$B/bench/vobb-bench-estimator" data/real/dino.off --m $1 --leaves $2 --roots $3 --ablation-boxes $3
done

echo "== variational builds of dino, each backend (same tree expected: cmp)"
build() {  # build LABEL BINARY ARGS...
  local label=$1 bin=$2
  shift 2
  timed "$label" timeout 240 "$bin" build data/real/dino.off -o "$O/$label.json" --quiet "$@"
}
for depth in 6 8; do
  [ -n "$OLD" ] && [ $depth = 6 ] && build d${depth}_gl_old "$OLD/vobb" --depth $depth --backend gl
  build d${depth}_gl "$B/app/vobb" --depth $depth --backend gl
  build d${depth}_cpu "$B/app/vobb" --depth $depth --backend cpu
  cmp "$O/d${depth}_gl.json" "$O/d${depth}_cpu.json" && echo "depth $depth: gl and cpu trees are the same bytes"
  [ -f "$O/d${depth}_gl_old.json" ] && cmp "$O/d${depth}_gl_old.json" "$O/d${depth}_gl.json" && echo "depth $depth: old and new gl trees are the same bytes"
done
build d6_m128_gl "$B/app/vobb" --depth 6 --m 128 --backend gl
build d6_m128_cpu "$B/app/vobb" --depth 6 --m 128 --backend cpu
cmp "$O/d6_m128_gl.json" "$O/d6_m128_cpu.json" && echo "depth 6, m 128: gl and cpu trees are the same bytes"
exit 0

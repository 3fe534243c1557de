#!/bin/bash
# The default objective (`omv`) against the paper's (`obv`) on a machine with a GPU and many
# cores, through the `vobb` command a user types: build time of each objective and each backend
# (CPU twin, GL, polyhedral solver), each tree's exact e from `vobb certify`, whether the GL
# and CPU-twin trees are the same bytes, the GL tests on that driver and the quick validation
# suite. The two objectives alternate, two rounds at depth 8, so their ratio compares like with
# like on one machine.
#
# Usage: bench/objective_device_bench.sh BUILD_DIR OUT_DIR [DEPTH8] [DEPTH12]
#   BUILD_DIR  a Release build (app/vobb and tests/fast_gl_tests are used)
#   OUT_DIR    where the trees, logs and the validation folder go
#   DEPTH8     the "depth 8" of the runs (default 8; a smaller one checks the script quickly)
#   DEPTH12    the deep build's depth (default 12)
# Needs data/real (data/fetch_meshes.sh).
set -u
B=${1:?BUILD_DIR}
O=${2:?OUT_DIR}
D8=${3:-8}
D12=${4:-12}
V="$B/app/vobb"
mkdir -p "$O"

wall() {  # wall LABEL COMMAND...: runs it, prints its wall and user seconds and exit status
  local label=$1 t0 rc
  shift
  t0=$(date +%s.%N)
  "$@"
  rc=$?
  python3 -c "import sys; print(f'[{sys.argv[1]}: {float(sys.argv[3]) - float(sys.argv[2]):.2f} s wall, rc {sys.argv[4]}]')" \
    "$label" "$t0" "$(date +%s.%N)" "$rc"
  return $rc
}
e_of() {  # e_of MESH TREE: the tree's exact e (certify's correctly rounded double)
  "$V" certify "data/real/$1.off" "$2" --json --quiet 2>/dev/null |
    python3 -c "import json, sys; d = json.load(sys.stdin); print(repr(d['weighted_error']), 'containment', d['containment']['ok'])"
}
build() {  # build LABEL MESH DEPTH ARGS...: one `vobb build`, timed; the tree is OUT/LABEL.json
  local label=$1 mesh=$2 depth=$3
  shift 3
  wall "$label" "$V" build "data/real/$mesh.off" -o "$O/$label.json" --depth "$depth" --quiet "$@"
}

echo "== machine"
date -u
echo "$(nproc) cores,$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || echo "no nvidia-smi"

echo "== the GL tests on this driver"
wall fast_gl_tests "$B/tests/fast_gl_tests" >"$O/fast_gl_tests.log" 2>&1
tail -1 "$O/fast_gl_tests.log"
grep -E "FAILED" "$O/fast_gl_tests.log" | head

echo "== dino, depth $D8: obv and the default alternated, two rounds; then GL and poly"
for round in 1 2; do
  build "dino$D8-obv-r$round" dino "$D8" --objective obv --backend cpu
  build "dino$D8-omv-r$round" dino "$D8" --backend cpu
done
build "dino$D8-omv-gl" dino "$D8" --backend gl
build "dino$D8-omv-poly" dino "$D8" --backend poly
build "dino$D8-obv-gl" dino "$D8" --objective obv --backend gl
cmp -s "$O/dino$D8-obv-r1.json" "$O/dino$D8-obv-r2.json" && echo "obv: both rounds the same bytes"
cmp -s "$O/dino$D8-omv-r1.json" "$O/dino$D8-omv-r2.json" && echo "omv: both rounds the same bytes"
for g in omv obv; do
  if cmp -s "$O/dino$D8-$g-r1.json" "$O/dino$D8-$g-gl.json"; then
    echo "$g: GL tree and CPU-twin tree are the same bytes"
  else
    echo "$g: GL tree differs from the CPU twin's"
  fi
done
python3 -c "import json, sys; t = json.load(open(sys.argv[1])); print(json.dumps({'boxes': [{k: n[k] for k in ('center', 'axes', 'half_extents')} for n in t['nodes'][:3]]}))" \
  "$O/dino$D8-omv-r1.json" >"$O/boxes3.json"
echo "GL renderer: $("$V" obv data/real/dino.off --boxes "$O/boxes3.json" --backend gl --m 32 --json 2>/dev/null |
  python3 -c "import json, sys; print(json.load(sys.stdin).get('renderer'))")"
for t in obv-r1 omv-r1 omv-gl omv-poly obv-gl; do
  echo "e dino$D8-$t: $(e_of dino "$O/dino$D8-$t.json")"
done

echo "== elephant and knot1, depth $D8: obv, then the default"
for mesh in elephant knot1; do
  build "$mesh$D8-obv" "$mesh" "$D8" --objective obv --backend cpu
  build "$mesh$D8-omv" "$mesh" "$D8" --backend cpu
  for g in obv omv; do echo "e $mesh$D8-$g: $(e_of "$mesh" "$O/$mesh$D8-$g.json")"; done
done

echo "== dino, depth $D12: obv, then the default, then the default with GL"
build "dino$D12-obv" dino "$D12" --objective obv --backend cpu
build "dino$D12-omv" dino "$D12" --backend cpu
build "dino$D12-omv-gl" dino "$D12" --backend gl
cmp -s "$O/dino$D12-omv.json" "$O/dino$D12-omv-gl.json" && echo "depth $D12: GL and CPU-twin trees are the same bytes"
echo "e dino$D12-omv:"
wall "certify dino$D12-omv" e_of dino "$O/dino$D12-omv.json"

echo "== the quick validation suite"
wall "validate quick" "$V" validate --suite quick --out "$O/validate-quick" --quiet >"$O/validate.log" 2>&1
tail -5 "$O/validate.log"
grep -iE "pass|fail" "$O/validate-quick/summary.md" 2>/dev/null | head -20
exit 0

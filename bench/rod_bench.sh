#!/usr/bin/env bash
# A thin closed rod of RINGS octagonal rings (radius 0.02, length 1.7, fan caps) along DIR:
# "diag" lies on a diagonal of its bounds, (1,1,1)/sqrt(3); "x" along an axis, for contrast.
# Its faces are slivers (rings 1.7 / RINGS apart, 0.015 around), and the ones of a quad are
# nearly coplanar, so the solidity check's predicates often fall back to exact arithmetic.
# Times `vobb info` (load, solidity) and `vobb obv --backend poly` on one box per 8 rings, each
# box around its rings' faces, against an older vobb when given; new and old alternate, twice
# each. Prints each run's wall seconds and, for obv, the faces the boxes' intervals visited.
# Usage: bench/rod_bench.sh VOBB OUT_DIR RINGS [OLD_VOBB] [DIR]
set -euo pipefail
vobb=$1 out=$2 rings=$3 old=${4:-} dir=${5:-diag}
mkdir -p "$out"
mesh="$out/rod_${dir}_$rings.off" boxes="$out/rod_${dir}_$rings.boxes.json"
python3 - "$mesh" "$boxes" "$rings" "$dir" <<'PY'
import json, math, sys
mesh, boxes_path, m, d = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
k, r, L, per = 8, 0.02, 1.7, 8
if d == "diag":
    a = [1 / math.sqrt(3)] * 3
    u = [1 / math.sqrt(2), -1 / math.sqrt(2), 0]
    w = [1 / math.sqrt(6), 1 / math.sqrt(6), -2 / math.sqrt(6)]
else:
    a, u, w = [1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]
V = []
for i in range(m):
    s = L * i / (m - 1)
    for j in range(k):
        t = 2 * math.pi * j / k
        V.append([s * a[c] + r * (math.cos(t) * u[c] + math.sin(t) * w[c]) for c in range(3)])
c0 = len(V)
V += [[0.0, 0.0, 0.0], [L * a[c] for c in range(3)]]
v = lambda i, j: i * k + j % k
F = []
for i in range(m - 1):
    for j in range(k):
        F += [(v(i, j), v(i, j + 1), v(i + 1, j + 1)), (v(i, j), v(i + 1, j + 1), v(i + 1, j))]
for j in range(k):
    F += [(c0, v(0, j + 1), v(0, j)), (c0 + 1, v(m - 1, j), v(m - 1, j + 1))]
with open(mesh, "w") as f:
    f.write(f"OFF\n{len(V)} {len(F)} 0\n")
    f.writelines("%r %r %r\n" % tuple(p) for p in V)
    f.writelines("3 %d %d %d\n" % t for t in F)
step, boxes = L / (m - 1), []
for i in range(0, m - 1, per):
    s0, s1 = i * step, min(m - 1, i + per) * step
    boxes.append({"center": [(s0 + s1) / 2 * a[c] for c in range(3)], "axes": [a, u, w],
                  "half_extents": [(s1 - s0) / 2 * 1.001, r * 1.001, r * 1.001]})
json.dump({"boxes": boxes}, open(boxes_path, "w"))
PY
secs() { echo "$2 - $1" | bc; }
run() {
  local label=$1 bin=$2 t0 t1 t2
  t0=$(date +%s.%N)
  "$bin" info "$mesh" >/dev/null
  t1=$(date +%s.%N)
  "$bin" obv "$mesh" --boxes "$boxes" --backend poly --json >"$out/obv_$label.json"
  t2=$(date +%s.%N)
  faces=$(python3 -c "import json,sys; print(sum(b['interval_faces'] for b in \
json.load(open(sys.argv[1]))['boxes']))" "$out/obv_$label.json")
  printf '%s %s %d rings: info %.2f s, obv --backend poly %.2f s (%s faces visited)\n' \
    "$label" "$dir" "$rings" "$(secs "$t0" "$t1")" "$(secs "$t1" "$t2")" "$faces"
}
for round in 1 2; do
  run new "$vobb"
  if [ -n "$old" ]; then run old "$old"; fi
done

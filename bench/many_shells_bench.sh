#!/usr/bin/env bash
# Loading a solid of many shells: COUNT disjoint tetrahedra (one shell each), through `vobb info`
# (load, exact solidity, volume), against an older vobb when given; new and old alternate, twice
# each. LAYOUT grid (default): unit tetrahedra on a grid 3 units apart. LAYOUT ray: tetrahedra
# 3 units apart along a fixed diagonal, turned and jittered. LAYOUT axis: unit tetrahedra 3
# units apart along x, so that the ray locate_point casts first (common/point_in_solid.cpp, along
# +x) from each shell's first vertex passes through the later ones. LAYOUT sheets: thin parallel
# tetrahedra 1e-6 apart across the plane z = -x, each shell's first vertex on the boundary of
# every other's bounding box, so that rays from it along +x, +y, -y, +z and -z meet the shells
# above or below it. Prints each run's wall seconds and the verdict line.
# Usage: bench/many_shells_bench.sh VOBB OUT_DIR COUNT [OLD_VOBB] [LAYOUT]
set -euo pipefail
vobb=$1 out=$2 count=$3 old=${4:-} layout=${5:-grid}
mkdir -p "$out"
mesh="$out/tets_${layout}_$count.off"
python3 - "$mesh" "$count" "$layout" <<'PY'
import random, sys
path, n, layout = sys.argv[1], int(sys.argv[2]), sys.argv[3]
ray = (0.5773502691896258, 0.3437184391289216, 0.7404171463391124)
rng = random.Random(1)
vertices = []
for k in range(n):
    if layout == "sheets":
        c, d = k * 1e-6, 2.5e-7
        o = (0, 0, 0)
        tet = ((0, 0, c), (1, 0, c - 1), (0.5, 1, c - 0.5), (0.5 + d, 1 / 3, c - 0.5 + d))
    elif layout == "axis":
        o = (3 * k, 0, 0)
        tet = ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))
    elif layout == "ray":
        o = [3 * k * ray[i] + rng.uniform(-0.02, 0.02) for i in range(3)]
        tet = ((-0.3, -0.3, -0.3), (0.6, -0.2, -0.1), (-0.2, 0.6, -0.1), (-0.1, -0.1, 0.6))
    else:
        o = (3 * (k % 100), 3 * (k // 100 % 100), 3 * (k // 10000))
        tet = ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))
    vertices += [tuple(a + b for a, b in zip(o, v)) for v in tet]
with open(path, "w") as f:
    f.write(f"OFF\n{4 * n} {4 * n} 0\n")
    for v in vertices:
        f.write("%r %r %r\n" % v)
    for k in range(n):
        b = 4 * k
        f.write(f"3 {b} {b + 2} {b + 1}\n3 {b} {b + 1} {b + 3}\n3 {b} {b + 3} {b + 2}\n"
                f"3 {b + 1} {b + 2} {b + 3}\n")
PY
run() {
  local label=$1 bin=$2 t0 t1
  t0=$(date +%s.%N)
  verdict=$("$bin" info "$mesh" | grep -i -m1 "verdict\|solid")
  t1=$(date +%s.%N)
  printf '%s %d shells: %.2f s  %s\n' "$label" "$count" "$(echo "$t1 - $t0" | bc)" "$verdict"
}
for round in 1 2; do
  run new "$vobb"
  if [ -n "$old" ]; then run old "$old"; fi
done

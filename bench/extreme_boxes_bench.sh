#!/usr/bin/env bash
# The variational builder (the default: CPU twin at m = 32, objective omv) on extreme solids,
# against OBB-Tree, and against an older vobb when given: each tree's build wall time and exact
# e (certify's default path). The solids, written to OUT_DIR: a cuboid 1e4 x 1 x 1e-4, a cuboid
# 1e30 x 1 x 1, a unit cube sheared by 1e8 (x += 1e8 z), and a closed plate 1 x 1 x 1e-3
# tessellated 32 x 32 (4,352 faces). The builds alternate new and old per solid.
# Usage: bench/extreme_boxes_bench.sh VOBB OUT_DIR DEPTH [OLD_VOBB]
set -euo pipefail
vobb=$1 out=$2 depth=$3 old=${4:-}
mkdir -p "$out"
python3 - "$out" <<'PY'
import sys
out = sys.argv[1]
V = [(i & 1, (i >> 1) & 1, (i >> 2) & 1) for i in range(8)]
Q = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
F = [t for a, b, c, d in Q for t in ((a, b, c), (a, c, d))]

def write(name, verts, faces):
    with open(f"{out}/{name}.off", "w") as f:
        f.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
        f.writelines("%r %r %r\n" % tuple(map(float, p)) for p in verts)
        f.writelines("3 %d %d %d\n" % t for t in faces)

write("cuboid_1e8", [(x * 1e4, y, z * 1e-4) for x, y, z in V], F)
write("cuboid_1e30", [(x * 1e30, y, z) for x, y, z in V], F)
write("sheared_1e8", [(x + 1e8 * z, y, z) for x, y, z in V], F)
n, t = 32, 1e-3
verts, index, faces = [], {}, []
def v(p):
    if p not in index:
        index[p] = len(verts)
        verts.append(p)
    return index[p]
def quad(a, b, c, d):
    faces.extend([(a, b, c), (a, c, d)])
g = lambda i: i / n
for i in range(n):
    for j in range(n):
        quad(v((g(i), g(j), 0)), v((g(i), g(j + 1), 0)), v((g(i + 1), g(j + 1), 0)), v((g(i + 1), g(j), 0)))
        quad(v((g(i), g(j), t)), v((g(i + 1), g(j), t)), v((g(i + 1), g(j + 1), t)), v((g(i), g(j + 1), t)))
for i in range(n):
    quad(v((g(i), 0, 0)), v((g(i + 1), 0, 0)), v((g(i + 1), 0, t)), v((g(i), 0, t)))
    quad(v((g(i), 1, 0)), v((g(i), 1, t)), v((g(i + 1), 1, t)), v((g(i + 1), 1, 0)))
    quad(v((0, g(i), 0)), v((0, g(i), t)), v((0, g(i + 1), t)), v((0, g(i + 1), 0)))
    quad(v((1, g(i), 0)), v((1, g(i + 1), 0)), v((1, g(i + 1), t)), v((1, g(i), t)))
write("plate_1e3", verts, faces)
PY
printf '%-12s %-10s %10s %26s\n' solid tree "build s" "e (exact)"
for solid in cuboid_1e8 cuboid_1e30 sheared_1e8 plate_1e3; do
  mesh=$out/$solid.off
  runs=("new:$vobb:")
  [ -n "$old" ] && runs+=("old:$old:")
  runs+=("obbtree:$vobb:--method obbtree")
  for run in "${runs[@]}"; do
    IFS=: read -r name bin flags <<<"$run"
    tree=$out/$solid.$name.json
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$bin" build "$mesh" -o "$tree" --depth "$depth" $flags --quiet 2>/dev/null
    t1=$(date +%s.%N)
    e=$("$vobb" certify "$mesh" "$tree" --json --quiet | python3 -c \
      'import json, sys; print(json.load(sys.stdin)["weighted_error"])')
    printf '%-12s %-10s %10.2f %26s\n' "$solid" "$name" "$(awk "BEGIN { print $t1 - $t0 }")" "$e"
  done
done

#!/usr/bin/env bash
# Loading a solid of many shells: COUNT disjoint unit tetrahedra on a grid 3 units apart (one
# shell each), through `vobb info` (load, exact solidity, volume), against an older vobb when
# given; new and old alternate, twice each. Prints each run's wall seconds and the verdict line.
# Usage: bench/many_shells_bench.sh VOBB OUT_DIR COUNT [OLD_VOBB]
set -euo pipefail
vobb=$1 out=$2 count=$3 old=${4:-}
mkdir -p "$out"
mesh="$out/tets_$count.off"
python3 - "$mesh" "$count" <<'PY'
import sys
path, n = sys.argv[1], int(sys.argv[2])
with open(path, "w") as f:
    f.write(f"OFF\n{4 * n} {4 * n} 0\n")
    for k in range(n):
        o = (3 * (k % 100), 3 * (k // 100 % 100), 3 * (k // 10000))
        for v in ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)):
            f.write("%d %d %d\n" % tuple(a + b for a, b in zip(o, v)))
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

#!/usr/bin/env bash
# What a user sees: `vobb obv` on the level-8, level-4 and root boxes of MESH's OBB-Tree
# baseline (depth 8), per backend, on one core (taskset) and on all; the seconds per box that
# obv reports (the batch's time per box) and the command's whole wall time.
# Usage: bench/poly_cli_bench.sh VOBB MESH OUT_DIR [M]
set -euo pipefail
vobb=$1 mesh=$2 out=$3 m=${4:-32}
mkdir -p "$out"
name=$(basename "$mesh" .off)
"$vobb" build "$mesh" -o "$out/$name.obbtree8.json" --method obbtree --depth 8 --quiet 2>/dev/null
for level in 8 4 0; do
  python3 - "$out/$name.obbtree8.json" "$level" "$out/$name.level$level.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
boxes = [{k: n[k] for k in ("center", "axes", "half_extents")} for n in t["nodes"] if n["level"] == int(sys.argv[2])]
json.dump({"boxes": boxes}, open(sys.argv[3], "w"))
PY
done
printf '%-8s %-6s %-5s %-6s %14s %12s\n' mesh level cores backend "ms per box" "wall s"
for level in 8 4 0; do
  boxes=$out/$name.level$level.json
  for cores in 1 all; do
    pin=(); [ "$cores" = 1 ] && pin=(taskset -c 0)
    for backend in poly cpu gl; do
      t0=$(date +%s.%N)
      "${pin[@]}" "$vobb" obv "$mesh" --boxes "$boxes" --backend "$backend" --m "$m" --json >"$out/obv.json" 2>/dev/null
      t1=$(date +%s.%N)
      python3 - "$out/obv.json" "$name" "$level" "$cores" "$backend" "$t0" "$t1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
b = sys.argv[5]
s = [e["seconds"] for box in d["boxes"] for e in box["estimates"] if e["backend"] == b]
print("%-8s %-6s %-5s %-6s %14.4f %12.2f   (%d boxes)" % (sys.argv[2], sys.argv[3], sys.argv[4], b,
      1e3 * sum(s) / len(s), float(sys.argv[7]) - float(sys.argv[6]), len(s)))
PY
    done
  done
done

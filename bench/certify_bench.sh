#!/usr/bin/env bash
# certify on prepared trees: wall seconds and peak memory (GNU time) of each run asked for, the
# weighted error printed, and the filter's fallbacks (boxes whose OBV or overlap term went to
# rationals, layers with a value rounded from rationals) read from --json.
# Usage: bench/certify_bench.sh VOBB OUT_DIR MESH:TREE:FLAGS...
#   FLAGS is certify's extra flags with ',' for ' ' (e.g. --path,both); "-" for none.
#   VOBB may be another build (an older vobb) for a ratio measured in the same run.
set -euo pipefail
vobb=$1 out=$2
shift 2
mkdir -p "$out"
printf '%-10s %-14s %-18s %9s %9s %22s %s\n' mesh tree flags "wall s" "peak MB" "e" "fallbacks (obv, overlap, rounded exactly)"
n=0
for spec in "$@"; do
  IFS=: read -r mesh tree flags <<<"$spec"
  extra=()
  [ "$flags" != "-" ] && IFS=, read -r -a extra <<<"$flags"
  n=$((n + 1))
  json=$out/run$n.json
  /usr/bin/time -f '%e %M' -o "$out/run$n.time" "$vobb" certify "$mesh" "$tree" --json --quiet "${extra[@]}" >"$json" || true
  read -r wall kb <"$out/run$n.time"
  summary=$(python3 - "$json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
levels = c.get("levels", [])
obv = c.get("exact_obv", "-")
over = sum(l.get("exact_overlap", 0) for l in levels) if levels and "exact_overlap" in levels[0] else "-"
by = ("omv_rounded_by", "sum_obv_rounded_by", "overlap_rounded_by")
rounded = sum(1 for l in levels if any(l.get(k) == "exact" for k in by)) if levels and by[0] in levels[0] else "-"
print("%22.17g %s, %s, %s" % (c["weighted_error"], obv, over, rounded))
PY
)
  printf '%-10s %-14s %-18s %9.1f %9.0f %s\n' "$(basename "$mesh" .off)" "$(basename "$tree" .json)" "$flags" \
         "$wall" "$((kb / 1024))" "$summary"
done

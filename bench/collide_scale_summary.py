#!/usr/bin/env python3
"""Summarises a collider-size sweep of `vobb collide --json` runs into the Markdown table of
docs/BENCHMARKS.md ("Does the collider size decide the reductions?").

Usage: collide_scale_summary.py DIR
DIR holds dyn_kK_sS.json (dynamic) and sta_kK_sS.json (static) runs for collider scale K and
seed S, each with three trees: the baseline (first), the variational tree and the collider-
margin tree. Per (mode, K): queries and touching queries, the baseline's box tests per
simulated second or per query, the share of the baseline's tests at levels 0 and 1, each
tree's box-test change in % (mean ± sample standard deviation over the seeds), the change
counting only levels 2 and below, and the variational tree's range over the seeds. A run that
disagrees with brute force stops the summary.
"""
import glob
import json
import re
import statistics
import sys


def signed(x, digits=1):
    """A change in %, with a typographic minus as the tables use."""
    return f"{x:+.{digits}f}".replace("-", "−")


def mean_sd(v):
    return signed(statistics.mean(v)) + (f" ± {statistics.stdev(v):.1f}" if len(v) > 1 else "")


def below_level_1(tree):
    return sum(tree["box_tests_by_level"][2:])


def main(folder):
    rows = {}
    for path in sorted(glob.glob(folder + "/*_k*_s*.json")):
        m = re.search(r"(dyn|sta)_k([0-9.]+)_s(\d+)\.json$", path)
        if not m:
            continue
        with open(path) as f:
            run = json.load(f)
        if not run["brute_force_agrees"]:
            sys.exit(f"{path}: a tree disagrees with brute force")
        base, var, mar = run["trees"][:3]
        levels = base["box_tests_by_level"]
        r = rows.setdefault((m.group(1), float(m.group(2))), {k: [] for k in
                            ("queries", "touching", "unit", "shared", "var", "mar", "var2", "mar2")})
        r["queries"].append(run["queries"])
        r["touching"].append(run["touching_queries"])
        r["unit"].append(base["box_tests_per_second"] if m.group(1) == "dyn" else base["box_tests_per_query"])
        r["shared"].append(100.0 * (levels[0] + levels[1]) / base["box_tests"])
        r["var"].append(-var["reduction_pct"])
        r["mar"].append(-mar["reduction_pct"])
        r["var2"].append(100.0 * (below_level_1(var) / below_level_1(base) - 1))
        r["mar2"].append(100.0 * (below_level_1(mar) / below_level_1(base) - 1))
    print("| mode | collider scale | seeds | queries per run (touching) | baseline box tests per s (dynamic) "
          "or per query (static) | levels 0–1 share of baseline tests % | variational % | margin 0.1 H % | "
          "variational, levels ≥ 2 % | margin, levels ≥ 2 % | variational seeds' range |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for mode, k in sorted(rows, key=lambda key: (key[0] != "dyn", key[1])):
        r = rows[(mode, k)]
        unit = statistics.mean(r["unit"])
        print(f"| {'dynamic' if mode == 'dyn' else 'static'} | {k:g} | {len(r['queries'])} | "
              f"{statistics.mean(r['queries']):,.0f} ({statistics.mean(r['touching']):,.0f}) | "
              f"{f'{unit:,.0f}' if unit > 1000 else f'{unit:.5g}'} | {statistics.mean(r['shared']):.1f} | "
              f"**{mean_sd(r['var'])}** | **{mean_sd(r['mar'])}** | {mean_sd(r['var2'])} | {mean_sd(r['mar2'])} | "
              f"{signed(min(r['var']))} … {signed(max(r['var']))} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])

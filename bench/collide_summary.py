#!/usr/bin/env python3
"""Summarises `vobb collide --json` runs of a baseline tree (first) against each later tree
(the variational tree, and the collider-margin tree when the run has one) into the Markdown
table of docs/BENCHMARKS.md (issue 7). A tree is named by its file name less the mesh and the
depth: dino_margin0.1_8.json is "margin0.1".

Usage: collide_summary.py RUN.json [RUN.json ...]
Runs are grouped by (mesh, depth, mode, tree); seeds of one group are averaged, and the spread is
the sample standard deviation over seeds (n - 1), left out for one seed. A run where a tree
disagrees with brute force, or FCL's answers disagree with brute force, stops the summary.
"""
import json
import re
import statistics
import sys
from collections import defaultdict


def change(a, b):
    """% change of b against a (negative: fewer)."""
    return 100.0 * (b / a - 1.0)


def main(paths):
    groups = defaultdict(list)
    for path in paths:
        with open(path) as f:
            run = json.load(f)
        base = run["trees"][0]
        if not run["brute_force_agrees"] or any(t["disagreements"] for t in run["trees"]):
            sys.exit(f"{path}: a tree disagrees with brute force")
        fcl_sides = [t for t in run["trees"] if t.get("fcl_bv_tests") is not None]
        if "fcl_own_obb_tree" in run:
            fcl_sides.append(run["fcl_own_obb_tree"])
        for t in fcl_sides:
            if t.get("fcl_answer_disagreements", t.get("answer_disagreements")) or \
               t.get("fcl_face_disagreements", t.get("face_disagreements")):
                sys.exit(f"{path}: FCL's answers disagree with brute force")
        mesh = run["mesh"].split("/")[-1].rsplit(".", 1)[0]
        names = set()
        for var in run["trees"][1:]:
            name = re.sub(r"_\d+$", "", var["file"].split("/")[-1].rsplit(".", 1)[0]).removeprefix(mesh + "_")
            if name in names:
                sys.exit(f"{path}: two trees named {name}")
            names.add(name)
            groups[(mesh, base["depth"], run["mode"], name)].append((run, base, var))

    def stat(values, fmt="{:+.1f}", spread_fmt=" ± {:.1f}"):
        mean = statistics.mean(values)
        spread = statistics.stdev(values) if len(values) > 1 else None
        text = fmt.format(mean) + (spread_fmt.format(spread) if spread is not None else "")
        return text.replace("-", "\u2212")  # the minus sign of the rest of docs/BENCHMARKS.md

    print("| mesh | D | mode | tree | seeds | queries per run (touching) | box tests per unit, baseline → tree "
          "| **box-test change %** | seeds' range | FCL on our nodes % | FCL raw % | levels ≥ 2 only % | leaf tests × | box + leaf % | narrow-phase time × |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for (mesh, depth, mode, name), runs in sorted(groups.items(), key=lambda g: (g[0][1], g[0][0], g[0][2], g[0][3] != "variational", g[0][3])):
        unit = [r["simulated_seconds"] if mode == "dynamic" else r["queries"] for r, _, _ in runs]
        per_base = statistics.mean(b["box_tests"] / u for (_, b, _), u in zip(runs, unit))
        per_var = statistics.mean(v["box_tests"] / u for (_, _, v), u in zip(runs, unit))
        box = [change(b["box_tests"], v["box_tests"]) for _, b, v in runs]
        fcl = [change(b["fcl_tree_node_bv_tests"], v["fcl_tree_node_bv_tests"]) for _, b, v in runs
               if b.get("fcl_tree_node_bv_tests") and v.get("fcl_tree_node_bv_tests")]
        raw = [change(b["fcl_bv_tests"], v["fcl_bv_tests"]) for _, b, v in runs
               if b.get("fcl_bv_tests") and v.get("fcl_bv_tests")]
        deep = [change(sum(b["box_tests_by_level"][2:]), sum(v["box_tests_by_level"][2:])) for _, b, v in runs]
        leaf = [v["leaf_tests"] / b["leaf_tests"] for _, b, v in runs]
        both = [change(b["box_tests"] + b["leaf_tests"], v["box_tests"] + v["leaf_tests"]) for _, b, v in runs]
        # Wall time of the traversals, as a ratio within each run (the trees ran on the same
        # queries, interleaved, so load affects both alike).
        seconds = [v["narrow_phase_seconds"] / b["narrow_phase_seconds"] for _, b, v in runs]
        queries = statistics.mean(r["queries"] for r, _, _ in runs)
        touching = statistics.mean(r["touching_queries"] for r, _, _ in runs)
        fmt_unit = "{:,.0f} /s" if mode == "dynamic" else "{:.2f}"
        print(f"| {mesh} | {depth} | {mode} | {name} | {len(runs)} | {queries:,.0f} ({touching:,.0f}) | "
              f"{fmt_unit.format(per_base)} → {fmt_unit.format(per_var)} | **{stat(box)}** | {stat([min(box)])} … {stat([max(box)])} | "
              f"{stat(fcl) if fcl else '-'} | {stat(raw) if raw else '-'} | {stat(deep)} | {stat(leaf, '{:.2f}', ' ± {:.2f}')} | {stat(both)} | {stat(seconds, '{:.2f}', ' ± {:.2f}')} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])

#!/usr/bin/env python3
"""The table of the sources' methods beside the project's (docs/results.md,
"The sources' methods"), from `truecut demo --paper` results.

    tools/paper_table.py out/papers/*/results.json

For each results.json: the optical-compensation source (Denkena et al.) on
its part, the implant, per operation it reports separately (peripheral and
face milling); the model-adaptation source (Sortino et al.) on its part,
benchmark004, as a whole; per row the
paper's figure, the source's recipe as this project runs it (stage
paper_denkena / paper_sortino) and the project's defaults on the same scan,
each as the RMS reduction the virtual CMM measures on those surfaces, and
the wall time of `truecut field` for each (audit.json, total_wall_s).
"""
import json
import math
import os
import sys

# Each source's experiment as this project rebuilds it (docs/parts.md).
EXPERIMENT = {"denkena": "implant", "sortino": "benchmark004"}
PAPER = {
    ("denkena", "peripheral"): "−65 % (peripheral milling)",
    ("denkena", "face"): "−85 % (face milling)",
    ("sortino", "all"): "no accuracy figure in the brief; field ~14 min (Matlab, 4 cores, "
                        "624,436 points, 113,896 faces)",
}


def group_rms(stage, names):
    n = sum(stage["surfaces"][s]["points"] for s in names if s in stage["surfaces"])
    if n == 0:
        return None
    ss = sum(stage["surfaces"][s]["points"] * stage["surfaces"][s]["rms_um"] ** 2
             for s in names if s in stage["surfaces"])
    return math.sqrt(ss / n)


def reduction(stages, key, names):
    if key not in stages:
        return None
    before, after = group_rms(stages["uncompensated"], names), group_rms(stages[key], names)
    if not before or after is None:
        return None
    return 100 * (1 - after / before), after


def cell(r):
    return "—" if r is None else f"{r[0]:.0f} % ({r[1]:.1f} µm)"


def field_seconds(part_dir, field_dir):
    path = os.path.join(part_dir, field_dir, "audit.json")
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as f:
        return json.load(f)["total_wall_s"]


def rows(path):
    with open(path, encoding="utf-8") as f:
        results = json.load(f)
    sigma = results["scanner_sigma_um"]
    for part in results["parts"]:
        part_dir = os.path.join(os.path.dirname(path), part["part"])
        stages = part["stages"]
        with open(os.path.join(part_dir, "part", "part.json"), encoding="utf-8") as f:
            meta = json.load(f)
        names = {s["id"]: s["name"] for s in meta["surfaces"] if s["compensate"]}
        groups = {"all": sorted(names.values())}
        for op in meta["operations"]:
            judged = [names[i] for i in op["surface_ids"] if i in names]
            groups.setdefault(op["strategy"], []).extend(judged)
        t_default = field_seconds(part_dir, "field_1")
        for source, key, field_dir in (("denkena", "paper_denkena", "field_denkena"),
                                       ("sortino", "paper_sortino", "field_sortino")):
            if key not in stages or EXPERIMENT[source] != part["part"]:
                continue
            t_paper = field_seconds(part_dir, field_dir)
            for group in ("peripheral", "face", "all"):
                if (source, group) not in PAPER or group not in groups:
                    continue
                surfaces = groups[group]
                ours = [f"{stages[k]['title']} {cell(reduction(stages, k, surfaces))}"
                        for k in ("realtime", "rewrite", "adapted") if k in stages]
                yield (f"| {source.capitalize()}: {group} | {part['part']} "
                       f"({', '.join(surfaces)}) | {sigma:g} | {PAPER[(source, group)]} | "
                       f"{cell(reduction(stages, key, surfaces))} | {'; '.join(ours)} | "
                       f"{t_paper:.1f} s / {t_default:.1f} s |")


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print("| source: operations | rebuilt here (judged surfaces) | scanner σ µm | the paper | "
          "the source's recipe here | the project's defaults, same scan | `truecut field` "
          "wall time: recipe / default |")
    print("|---|---|---|---|---|---|---|")
    for path in paths:
        for row in rows(path):
            print(row)


if __name__ == "__main__":
    main(sys.argv[1:])

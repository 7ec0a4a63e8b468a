#!/usr/bin/env python3
"""Markdown tables of one or more `truecut demo` results.json files.

    tools/results_tables.py out/demo/results.json [more results.json ...]

Prints, per part and scanner sigma, the stage table (RMS, max, P95, std of
the judged CMM points, RMS reduction against the uncompensated part) and
the per-surface table (RMS / max), and, when the demo machined the
error-free reference, the machine's share: each CMM point's deviation minus
the reference part's at the same point (what the program itself leaves —
scallops, cusps — taken out). docs/results.md is made of its output.
"""
import csv
import json
import math
import os
import sys


def stage_rows(part):
    stages = part["stages"]
    before = stages["uncompensated"]["all_judged"]["rms_um"]
    rows = ["| stage | RMS µm | max µm | P95 µm | std µm | RMS reduction |",
            "|---|---|---|---|---|---|"]
    for key, st in stages.items():
        a = st["all_judged"]
        if key == "uncompensated":
            cut = "—"
        elif key == "ideal":
            cut = "reference"
        else:
            cut = f"{100 * (1 - a['rms_um'] / before):.0f} %"
        rows.append(f"| {st['title']} | {a['rms_um']:.1f} | {a['max_um']:.1f} | "
                    f"{a['p95_um']:.1f} | {a['std_um']:.1f} | {cut} |")
    return rows


def surface_rows(part):
    stages = part["stages"]
    keys = list(stages)
    rows = ["| surface | " + " | ".join(stages[k]["title"] for k in keys) + " |",
            "|---" * (len(keys) + 1) + "|"]
    for name in stages["uncompensated"]["surfaces"]:
        cells = []
        for k in keys:
            s = stages[k]["surfaces"].get(name)
            cells.append(f"{s['rms_um']:.1f} / {s['max_um']:.1f}" if s else "—")
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    return rows


def read_cmm(path):
    """(x, y, z) -> (surface, deviation µm) of the valid points of a cmm.csv."""
    points = {}
    with open(path, encoding="utf-8") as f:
        for row in csv.DictReader(f):
            if row["valid"] == "1":
                key = (row["x"], row["y"], row["z"])
                points[key] = (int(row["surface"]), 1000 * float(row["deviation_mm"]))
    return points


def machine_share_rows(part, part_dir):
    stages = part["stages"]
    if "ideal" not in stages:
        return []
    ids = set()
    ideal = read_cmm(os.path.join(part_dir, "ideal", "cmm.csv"))
    judged = {n for n in stages["uncompensated"]["surfaces"]}
    rows = ["| stage | points | RMS µm | mean µm | std µm | RMS reduction |",
            "|---|---|---|---|---|---|"]
    before = None
    # Judged surfaces by id: the ids whose points the results count.
    with open(os.path.join(part_dir, "part", "part.json"), encoding="utf-8") as f:
        for sf in json.load(f)["surfaces"]:
            if sf["name"] in judged:
                ids.add(sf["id"])
    for key, st in stages.items():
        if key == "ideal":
            continue
        pts = read_cmm(os.path.join(part_dir, key, "cmm.csv"))
        d = [dev - ideal[p][1] for p, (sid, dev) in pts.items() if sid in ids and p in ideal]
        if not d:
            continue
        mean = sum(d) / len(d)
        rms = math.sqrt(sum(x * x for x in d) / len(d))
        std = math.sqrt(max(rms * rms - mean * mean, 0.0))
        if key == "uncompensated":
            before = rms
            cut = "—"
        else:
            cut = f"{100 * (1 - rms / before):.0f} %" if before else ""
        rows.append(f"| {st['title']} | {len(d)} | {rms:.1f} | {mean:.1f} | {std:.1f} | {cut} |")
    return rows


def main(paths):
    if not paths:
        sys.exit(__doc__)
    for path in paths:
        with open(path, encoding="utf-8") as f:
            results = json.load(f)
        sigma = results["scanner_sigma_um"]
        for part in results["parts"]:
            print(f"### {part['part']}, scanner σ = {sigma:g} µm "
                  f"(demo wall time {part['wall_s']:.0f} s)\n")
            print("\n".join(stage_rows(part)))
            print("\nPer surface (RMS / max µm):\n")
            print("\n".join(surface_rows(part)))
            share = machine_share_rows(part, os.path.join(os.path.dirname(path), part["part"]))
            if share:
                print("\nMachine's share (deviation minus the error-free machine's at the same "
                      "CMM point):\n")
                print("\n".join(share))
            print()


if __name__ == "__main__":
    main(sys.argv[1:])

#!/usr/bin/env python3
"""Markdown tables of one or more `truecut demo` results.json files.

    tools/results_tables.py out/demo/results.json [more results.json ...]

Prints, per part and scanner sigma, the stage table (RMS, max, P95, std of
the judged CMM points, RMS reduction against the uncompensated part) and
the per-surface table (RMS / max). docs/results.md is made of its output.
"""
import json
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
            print()


if __name__ == "__main__":
    main(sys.argv[1:])

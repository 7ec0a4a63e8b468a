#!/usr/bin/env python3
"""Closed-loop sweep of `truecut field` settings on the implant (docs/offline.md,
"Noise: compensate only what is measured").

Takes a finished `truecut demo --part implant` folder (its part/ and its
uncompensated/machined.stl), then for every scanner sigma, scan seed and
field setting: scan the uncompensated part, build the field, machine part 2
with it and probe it with a dense, noiseless virtual CMM (the truth: every
0.25 mm of the judged surfaces). Prints per surface the mean and the spread
(std) of the deviation, averaged over the seeds, and the same for the
uncompensated part.

    tools: build/truecut demo --part implant --out out/imp
           bench/implant_noise_sweep.py out/imp/implant [--sigmas 20,50] [--seeds 3]
"""
import argparse
import csv
import math
import os
import subprocess
import sys

CONFIGS = {
    # name: extra `truecut field` options on top of the demo's; "before" runs
    # the truecut given with --before (the code before the noise work)
    "before": ["--spacing", "0.1"],
    "default": ["--spacing", "0.1"],
    "no significance test": ["--spacing", "0.1", "--significance", "0"],
    "default, remove RBM": ["--spacing", "0.1", "--remove-rbm"],
    "default, smoothness 1": ["--spacing", "0.1", "--smoothness", "1"],
    "vertices, kb/kc 0.2": ["--spacing", "0", "--kb-kc", "0.2"],
    "vertices, kb/kc 1": ["--spacing", "0", "--kb-kc", "1"],
    "vertices, kb/kc 5": ["--spacing", "0", "--kb-kc", "5"],
}


def run(cmd, cwd):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("failed: %s\n%s%s" % (" ".join(cmd), r.stdout, r.stderr))
    return r.stdout


def surface_stats(cmm_csv, names):
    by = {}
    with open(cmm_csv) as f:
        for row in csv.DictReader(f):
            if row["valid"] != "1":
                continue
            by.setdefault(names[int(row["surface"])], []).append(1000 * float(row["deviation_mm"]))
    out = {}
    everything = []
    for name, d in by.items():
        mean = sum(d) / len(d)
        std = math.sqrt(sum((x - mean) ** 2 for x in d) / len(d))
        rms = math.sqrt(sum(x * x for x in d) / len(d))
        out[name] = (mean, std, rms)
        everything += d
    mean = sum(everything) / len(everything)
    out["all judged"] = (mean, math.sqrt(sum((x - mean) ** 2 for x in everything) / len(everything)),
                         math.sqrt(sum(x * x for x in everything) / len(everything)))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("demo_part_dir")
    ap.add_argument("--truecut", default=os.path.abspath("build/truecut"))
    ap.add_argument("--before", help="truecut of the code before, for the 'before' setting")
    ap.add_argument("--sigmas", default="20,50")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--configs", default="|".join(CONFIGS), help="names separated by |")
    ap.add_argument("--work", default="sweep")
    a = ap.parse_args()
    d = os.path.abspath(a.demo_part_dir)
    tc = a.truecut
    import json
    part = json.load(open(os.path.join(d, "part", "part.json")))
    names = {s["id"]: s["name"] for s in part["surfaces"]}
    datum = ",".join(str(s["id"]) for s in part["surfaces"]
                     if not s["compensate"] and not s["name"].endswith("bottom"))
    work = os.path.join(d, a.work)
    os.makedirs(work, exist_ok=True)
    truth = ["--nominal", "part/nominal.stl", "--part", "part/part.json", "--spacing", "0.25",
             "--sigma-um", "0"]
    run([tc, "cmm", "uncompensated/machined.stl", *truth, "--out",
         os.path.join(work, "uncompensated_dense.csv")], d)
    base = surface_stats(os.path.join(work, "uncompensated_dense.csv"), names)
    results = {}
    for sigma in a.sigmas.split(","):
        for seed in range(1, a.seeds + 1):
            scan = os.path.join(work, "scan_s%s_%d.ply" % (sigma, seed))
            run([tc, "scan", "uncompensated/machined.stl", "--out", scan + ".cloud.ply", "--mesh-out",
                 scan, "--sigma-um", sigma, "--seed", str(1000 + seed)], d)
            for name in a.configs.split("|"):
                key = "%s_s%s_%d" % ("".join(c if c.isalnum() else "_" for c in name), sigma, seed)
                out = os.path.join(work, key)
                if name == "before" and not a.before:
                    continue
                field = [a.before if name == "before" else tc, "field", "part/nominal.stl", scan, "--program", "part/program.ngc",
                         "--tools", "part/tools.tbl", "--part", "part/part.json", "--resolution",
                         "1", "--edge-exclusion", "0.2", "--out", out + "_field", "--quiet"]
                if datum:
                    field += ["--datum", datum]
                summary = run(field + CONFIGS[name], d)
                run([tc, "run", "part/machine.json", "part/program.ngc", "--out", out + "_run",
                     "--dexel-spacing", "0.1", "--nominal", "part/nominal.stl", "--part",
                     "part/part.json", "--tools", "part/tools.tbl", "--field",
                     out + "_field/field.tcf"], d)
                run([tc, "cmm", out + "_run/machined.stl", *truth, "--out", out + "_cmm.csv"], d)
                st = surface_stats(out + "_cmm.csv", names)
                results.setdefault((sigma, name), []).append(st)
                top = [l for l in summary.splitlines() if l.startswith("surface 5:")]
                print("sigma %s seed %d %-24s top %+5.1f/%4.1f  all %+5.1f/%4.1f  %s" % (
                    sigma, seed, name, *st["shaft_top"][:2], *st["all judged"][:2],
                    top[0] if top else ""), flush=True)
    surfaces = [n for n in base if n != "all judged"] + ["all judged"]
    print("\nper surface: RMS over the seeds of the surface's mean deviation / mean over the seeds of"
          " its std, um (dense noiseless CMM, 0.25 mm), %d seeds" % a.seeds)
    print("%-8s %-24s " % ("sigma", "setting") + " ".join("%-14s" % s for s in surfaces))
    print("%-8s %-24s " % ("-", "uncompensated") +
          " ".join("%6.1f / %4.1f  " % (abs(base[s][0]), base[s][1]) for s in surfaces))
    for (sigma, name), runs in results.items():
        row = []
        for s in surfaces:
            m = math.sqrt(sum(r[s][0] ** 2 for r in runs) / len(runs))
            sd = sum(r[s][1] for r in runs) / len(runs)
            row.append("%6.1f / %4.1f  " % (m, sd))
        print("%-8s %-24s " % (sigma, name) + " ".join(row))


if __name__ == "__main__":
    main()

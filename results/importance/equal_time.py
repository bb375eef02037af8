#!/usr/bin/env python3
"""Equal-time comparison of importance caching with the many-light baselines, from a `cachert experiment`
results.csv (rows `power:N` and `uniform:N` are the baselines with N VPL draws per sub-pixel sample: VPLs
chosen in proportion to their power, or uniformly). For every scene, placement and budget: the mean over
seeds of RMSE, HDR-FLIP and wall seconds, each baseline's RMSE and FLIP at the same time (interpolated
linearly in log-time/log-error between its two nearest sample counts, extrapolated as error ∝ t^-1/2 outside
them), and the ratio baseline / importance caching (> 1: importance caching ahead).
With a second results.csv, the baselines are taken from it instead (say, a run with `--set splitcone=0`:
the standard many-light estimators without the near-specular split, against the same reference).
Standard library only.  Usage: equal_time.py results.csv [baselines.csv]"""
import csv, math, sys
from collections import defaultdict

BASELINES = ("power", "uniform")
rows = list(csv.DictReader(open(sys.argv[1])))
base_rows = list(csv.DictReader(open(sys.argv[2]))) if len(sys.argv) > 2 else rows
scenes = list(dict.fromkeys(r["scene"] for r in rows))


def at(base, t, k):
    """Baseline error k (1 RMSE, 2 FLIP) at time t."""
    if t <= base[0][0]:
        return base[0][k] * math.sqrt(base[0][0] / t)
    if t >= base[-1][0]:
        return base[-1][k] * math.sqrt(base[-1][0] / t)
    for (t0, *a), (t1, *b) in zip(base, base[1:]):
        if t0 <= t <= t1:
            f = math.log(t / t0) / math.log(t1 / t0)
            return math.exp(math.log(a[k - 1]) * (1 - f) + math.log(b[k - 1]) * f)


for scene in scenes:
    bases = {}
    for label in BASELINES:
        b = sorted((float(r["total_s"]), float(r["rmse"]), float(r["flip"]))
                   for r in base_rows if r["scene"] == scene and r["placement"].startswith(label + ":"))
        if b:
            bases[label] = b
    groups = defaultdict(list)
    for r in rows:
        if r["scene"] == scene and ":" not in r["placement"] and r["placement"] != "none":
            groups[(int(r["caches"]), r["placement"])].append(r)
    print(f"\n{scene}:")
    for label, b in bases.items():
        print(f"- {label} baseline " + ", ".join(f"{t:.2f} s: RMSE {e:.5f} FLIP {f:.4f}" for t, e, f in b))
    head = "| caches | placement | s | RMSE (min–max) |" + "".join(f" {l} RMSE | ratio |" for l in bases)
    head += " FLIP (min–max) |" + "".join(f" {l} FLIP | ratio |" for l in bases)
    print("\nAt equal time:\n\n" + head)
    print("|" + "---|" * (4 + 2 * len(bases) + 1 + 2 * len(bases)))
    for (caches, placement), g in sorted(groups.items()):
        t = sum(float(r["total_s"]) for r in g) / len(g)
        e = [float(r["rmse"]) for r in g]; f = [float(r["flip"]) for r in g]
        me, mf = sum(e) / len(e), sum(f) / len(f)
        line = f"| {caches} | {placement} | {t:.2f} | {me:.5f} ({min(e):.5f}–{max(e):.5f}) |"
        for b in bases.values():
            pe = at(b, t, 1)
            line += f" {pe:.5f} | {pe / me:.2f} |"
        line += f" {mf:.4f} ({min(f):.4f}–{max(f):.4f}) |"
        for b in bases.values():
            pf = at(b, t, 2)
            line += f" {pf:.4f} | {pf / mf:.2f} |"
        print(line)

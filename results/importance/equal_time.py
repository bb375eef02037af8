#!/usr/bin/env python3
"""Equal-time comparison of importance caching with the power-sampling baseline, from a `cachert experiment`
results.csv (rows `power:N` are the baseline with N VPL draws per sub-pixel sample). For every scene, placement
and budget: the mean over seeds of RMSE, HDR-FLIP and wall seconds, the baseline's RMSE and FLIP at the same
time (interpolated linearly in log-time/log-error between its two nearest sample counts, extrapolated as
error ∝ t^-1/2 outside them), and the ratio baseline / importance caching (> 1: importance caching ahead).
Standard library only.  Usage: equal_time.py results.csv"""
import csv, math, sys
from collections import defaultdict

rows = list(csv.DictReader(open(sys.argv[1])))
scenes = list(dict.fromkeys(r["scene"] for r in rows))
for scene in scenes:
    base = sorted(((float(r["total_s"]), float(r["rmse"]), float(r["flip"]))
                   for r in rows if r["scene"] == scene and r["placement"].startswith("power:")))
    def at(t, k):
        if t <= base[0][0]:
            return base[0][k] * math.sqrt(base[0][0] / t)
        if t >= base[-1][0]:
            return base[-1][k] * math.sqrt(base[-1][0] / t)
        for (t0, *a), (t1, *b) in zip(base, base[1:]):
            if t0 <= t <= t1:
                f = math.log(t / t0) / math.log(t1 / t0)
                return math.exp(math.log(a[k - 1]) * (1 - f) + math.log(b[k - 1]) * f)
    groups = defaultdict(list)
    for r in rows:
        if r["scene"] == scene and ":" not in r["placement"] and r["placement"] != "none":
            groups[(int(r["caches"]), r["placement"])].append(r)
    print(f"\n{scene}: power baseline " + ", ".join(f"{t:.2f} s: RMSE {e:.5f} FLIP {f:.4f}" for t, e, f in base))
    print("\n| caches | placement | s | RMSE (min–max) | power RMSE at equal time | ratio | FLIP (min–max) | power FLIP | ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (caches, placement), g in sorted(groups.items()):
        t = sum(float(r["total_s"]) for r in g) / len(g)
        e = [float(r["rmse"]) for r in g]; f = [float(r["flip"]) for r in g]
        me, mf = sum(e) / len(e), sum(f) / len(f)
        pe, pf = at(t, 1), at(t, 2)
        print(f"| {caches} | {placement} | {t:.2f} | {me:.5f} ({min(e):.5f}–{max(e):.5f}) | {pe:.5f} | {pe / me:.2f} "
              f"| {mf:.4f} ({min(f):.4f}–{max(f):.4f}) | {pf:.4f} | {pf / mf:.2f} |")

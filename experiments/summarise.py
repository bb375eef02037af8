#!/usr/bin/env python3
"""Compact view of an experiment's results.csv for experiments/README.md: per scene and budget, each plain
cache method's mean RMSE and HDR-FLIP over seeds as a ratio to IM's, marked + (clearly lower than IM) or -
(clearly higher) when the difference exceeds two standard errors, as `cachert experiment`'s tables do.

    python3 experiments/summarise.py experiments/results/ao/results.csv [placements...]
"""
import csv
import math
import statistics
import sys
from collections import defaultdict


def main():
    path = sys.argv[1]
    methods = sys.argv[2:] or ["sd", "sd+as", "vgc", "vgc+as", "vgc+dgs", "vgc+dgs:diff", "vgc+dgs:geom"]
    runs = defaultdict(list)
    for r in csv.DictReader(open(path)):
        if r["status"] != "ok" or r["varied"] or r["samples"]:
            continue
        runs[(r["scene"] + " " + r["application"], int(r["caches"]), r["placement"])].append((float(r["rmse"]), float(r["flip"])))
    cells = sorted({(s, c) for s, c, _ in runs})
    print("| scene, application | caches | IM RMSE / FLIP | " + " | ".join(methods) + " |")
    print("|---|---|---|" + "---|" * len(methods))
    for scene, caches in cells:
        im = runs.get((scene, caches, "im"))
        if not im:
            continue
        row = [scene, str(caches), "%.5f / %.5f" % tuple(statistics.mean(v[i] for v in im) for i in (0, 1))]
        for m in methods:
            rs = runs.get((scene, caches, m))
            if not rs:
                row.append("—")
                continue
            parts = []
            for i in (0, 1):
                a, b = [v[i] for v in rs], [v[i] for v in im]
                ma, mb = statistics.mean(a), statistics.mean(b)
                se = math.sqrt(sum((statistics.stdev(x) ** 2 / len(x)) if len(x) > 1 else 0.0 for x in (a, b)))
                mark = "+" if mb - ma > 2 * se else "-" if ma - mb > 2 * se else ""
                parts.append("%.2f%s" % (ma / mb, mark))
            row.append(" / ".join(parts))
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes envmap.pfm: a 24x12 (not a power of two, so pbrt-v3 resamples it) smooth colourful map with one
bright region, little-endian PF, bottom row first. Deterministic; no dependencies."""
import math, struct, sys
W, H = 24, 12
rows = []
for y in range(H):  # y = 0 is the top row (theta = 0)
    row = []
    for x in range(W):
        s, t = (x + 0.5) / W, (y + 0.5) / H
        r = 0.4 + 0.3 * math.sin(2 * math.pi * s)
        g = 0.3 + 0.25 * math.cos(math.pi * t)
        b = 0.2 + 0.15 * math.sin(4 * math.pi * s + 1.0)
        d2 = ((s - 0.3) * 3) ** 2 + ((t - 0.35) * 4) ** 2
        sun = 4.0 * math.exp(-d2 * 4)
        row.append((r + sun, g + 0.8 * sun, b + 0.5 * sun))
    rows.append(row)
out = sys.argv[1] if len(sys.argv) > 1 else "envmap.pfm"
with open(out, "wb") as f:
    f.write(b"PF\n%d %d\n-1\n" % (W, H))
    for row in reversed(rows):
        for px in row:
            f.write(struct.pack("<3f", *px))

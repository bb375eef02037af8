#!/usr/bin/env python3
"""Mean per channel of PFM images and, given two, the RMSE between them (over all channels).

Used only to fill README.md here; no test depends on it. Reads pbrt-v3's float32 PFMs with the standard
library alone.
usage: pfmstats.py A.pfm [B.pfm]
"""
import struct
import sys


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    kind, dims, scale = parts[0].strip(), parts[1].split(), float(parts[2])
    if kind != b"PF":
        sys.exit(f"{path}: not a colour PFM")
    w, h = int(dims[0]), int(dims[1])
    fmt = ("<" if scale < 0 else ">") + "f" * (w * h * 3)
    pix = struct.unpack(fmt, parts[3][: w * h * 12])
    return w, h, pix


def main():
    w, h, a = read_pfm(sys.argv[1])
    n = w * h
    means = [sum(a[c::3]) / n for c in range(3)]
    bad = sum(1 for v in a if v != v or v in (float("inf"), float("-inf")))
    out = f"{w}x{h} mean {means[0]:.4f} {means[1]:.4f} {means[2]:.4f} max {max(a):.3f} nonfinite {bad}"
    if len(sys.argv) > 2:
        _, _, b = read_pfm(sys.argv[2])
        rmse = (sum((x - y) ** 2 for x, y in zip(a, b)) / len(a)) ** 0.5
        out += f" rmse {rmse:.5f}"
    print(out)


main()

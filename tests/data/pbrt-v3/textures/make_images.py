#!/usr/bin/env python3
"""Writes the small texture images the texture scenes read (standard library only, deterministic)."""
import struct
import zlib


def values(n, seed):
    """n pseudo-random bytes from a fixed linear congruential generator."""
    out, x = [], seed
    for _ in range(n):
        x = (1103515245 * x + 12345) % (1 << 31)
        out.append((x >> 16) & 255)
    return out


def png(path, w, h, rgb):
    """8-bit RGB PNG; rgb is a list of h rows (top first) of w (r, g, b) tuples."""
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rgb)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    open(path, "wb").write(data)
    return data


def tga(path, w, h, rgb):
    """Uncompressed 24-bit TGA stored bottom row first (the format's default origin), pixels as BGR."""
    header = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, w, h, 24, 0)
    body = b"".join(bytes((b, g, r)) for row in reversed(rgb) for (r, g, b) in row)
    open(path, "wb").write(header + body)


def pfm(path, w, h, rgb):
    """Little-endian colour PFM; rows are written bottom first, as the format requires."""
    head = b"PF\n%d %d\n-1\n" % (w, h)
    body = b"".join(struct.pack("<3f", *px) for row in reversed(rgb) for px in row)
    open(path, "wb").write(head + body)


def grid(w, h, seed):
    v = values(3 * w * h, seed)
    return [[tuple(v[3 * (y * w + x) + c] for c in range(3)) for x in range(w)] for y in range(h)]


checker8 = grid(8, 8, 1)
data = png("rand8.png", 8, 8, checker8)
png("rand6x5.png", 6, 5, grid(6, 5, 2))
tga("rand8.tga", 8, 8, grid(8, 8, 3))
# A linear float image with values above 1 (4 columns, 4 rows).
f = grid(4, 4, 4)
pfm("rand4.pfm", 4, 4, [[tuple(c / 100.0 for c in px) for px in row] for row in f])
# The same PNG cut short in its image data: pbrt-v3 cannot decode it.
open("truncated.png", "wb").write(data[: len(data) // 2])

#!/usr/bin/env python3
"""Writes torus.ply: a torus (major radius 1, minor radius 0.35, axis +z, centred at the origin) as a binary
little-endian PLY with per-vertex normals, 24 x 12 segments (288 vertices, 576 triangles).
Run from this folder: python3 make_torus.py"""
import math
import struct

U, V, R, r = 24, 12, 1.0, 0.35
verts, faces = [], []
for i in range(U):
    a = 2 * math.pi * i / U
    for j in range(V):
        b = 2 * math.pi * j / V
        n = (math.cos(a) * math.cos(b), math.sin(a) * math.cos(b), math.sin(b))
        p = ((R + r * math.cos(b)) * math.cos(a), (R + r * math.cos(b)) * math.sin(a), r * math.sin(b))
        verts.append(p + n)
for i in range(U):
    for j in range(V):
        k = lambda di, dj: ((i + di) % U) * V + (j + dj) % V
        faces += [(k(0, 0), k(1, 0), k(1, 1)), (k(0, 0), k(1, 1), k(0, 1))]
header = (
    "ply\nformat binary_little_endian 1.0\ncomment made by make_torus.py\n"
    f"element vertex {len(verts)}\n"
    "property float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
)
with open("torus.ply", "wb") as f:
    f.write(header.encode("ascii"))
    for v in verts:
        f.write(struct.pack("<6f", *v))
    for t in faces:
        f.write(struct.pack("<B3i", 3, *t))

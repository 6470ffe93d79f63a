#!/usr/bin/env python3
"""Renders a coloured terrain PLY written by `lodkit terrain` (binary little-endian, float x y z,
per-face uchar red green blue) to a PNG with matplotlib: flat face colours times Lambert shading.

    /usr/bin/python3 scripts/render-terrain.py data/terrain.ply docs/images/terrain.png
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_terrain_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    counts = {line.split()[1]: int(line.split()[2]) for line in header if line.startswith("element")}
    if "format binary_little_endian 1.0" not in header or "property uchar red" not in header:
        sys.exit(f"{path}: expected a coloured binary PLY from `lodkit terrain --colour`")
    nv, nf = counts["vertex"], counts["face"]
    vertices = np.frombuffer(data, dtype="<f4", count=3 * nv, offset=end).reshape(nv, 3)
    face_type = np.dtype([("n", "u1"), ("v", "<i4", 3), ("rgb", "u1", 3)])
    faces = np.frombuffer(data, dtype=face_type, count=nf, offset=end + 12 * nv)
    return vertices.astype(float), faces["v"], faces["rgb"] / 255.0


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    vertices, triangles, colours = read_terrain_ply(sys.argv[1])
    corners = vertices[triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True) + 1e-30
    light = np.array([-0.4, -0.6, 0.7])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.clip(normals @ light, 0, 1)
    fig = plt.figure(figsize=(8, 5.5), dpi=100)
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Poly3DCollection(corners, facecolors=colours * shade[:, None], linewidths=0))
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], lo[2] + (hi[0] - lo[0]) * 0.6)
    ax.set_box_aspect((1, (hi[1] - lo[1]) / (hi[0] - lo[0]), 0.6), zoom=1.25)
    ax.view_init(elev=28, azim=-60)
    ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(sys.argv[2], bbox_inches="tight")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes OFF meshes whose faces crowd around one vertex or one edge.

double-cone K: a closed double cone, K triangles from each of two apexes to a unit circle.
Each apex is shared by K faces, where a search over overlapping face boxes is quadratic
(every face's box holds its apex).
crowded-edge K: K triangles on one edge, their third vertices on a circle around it (a
non-manifold edge; the faces meet only along it).
Used by vobb-bench-self-intersections.
Usage: fan_meshes.py double-cone|crowded-edge K OUT.off
"""
import math
import sys


def double_cone(k):
    verts = [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    verts += [(math.cos(2 * math.pi * i / k), math.sin(2 * math.pi * i / k), 0.0) for i in range(k)]
    faces = []
    for i in range(k):
        a, b = 2 + i, 2 + (i + 1) % k
        faces += [(0, a, b), (1, b, a)]
    return verts, faces


def crowded_edge(k):
    verts = [(0.0, 0.0, 0.0), (0.0, 0.0, 1.0)]
    verts += [(math.cos(2 * math.pi * i / k), math.sin(2 * math.pi * i / k), 0.5) for i in range(k)]
    return verts, [(0, 1, 2 + i) for i in range(k)]


def main():
    shapes = {"double-cone": double_cone, "crowded-edge": crowded_edge}
    if len(sys.argv) != 4 or sys.argv[1] not in shapes:
        sys.exit(__doc__)
    verts, faces = shapes[sys.argv[1]](int(sys.argv[2]))
    with open(sys.argv[3], "w") as f:
        f.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
        f.writelines("%.17g %.17g %.17g\n" % v for v in verts)
        f.writelines("3 %d %d %d\n" % t for t in faces)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes a closed double cone as OFF: K triangles from each of two apexes to a unit circle.

Each apex is shared by K faces, the case where a search over overlapping face boxes is
quadratic (every face's box holds its apex). Used by vobb-bench-self-intersections.
Usage: double_cone.py K OUT.off
"""
import math
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    k, out = int(sys.argv[1]), sys.argv[2]
    verts = [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    verts += [(math.cos(2 * math.pi * i / k), math.sin(2 * math.pi * i / k), 0.0) for i in range(k)]
    faces = []
    for i in range(k):
        a, b = 2 + i, 2 + (i + 1) % k
        faces += [(0, a, b), (1, b, a)]
    with open(out, "w") as f:
        f.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
        f.writelines("%.17g %.17g %.17g\n" % v for v in verts)
        f.writelines("3 %d %d %d\n" % t for t in faces)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Writes OFF meshes whose faces crowd around one vertex or one edge, or cross each other.

double-cone K: a closed double cone, K triangles from each of two apexes to a unit circle.
Each apex is shared by K faces, where a search over overlapping face boxes is quadratic
(every face's box holds its apex).
crowded-edge K: K triangles on one edge, their third vertices on a circle around it (a
non-manifold edge; the faces meet only along it).
spikes K: K closed thin tetrahedra (4 K faces), each from a random point on the unit sphere
through the centre to the opposite side, so nearly every pair of spikes crosses near the centre:
about 4 K^2 intersecting pairs of faces (crossing sheets, where counting them all is quadratic).
rim-fan-cylinder K: a closed cylinder of radius 1 and height 1, K quads around, whose caps are
written as K-gons; the reader fan-triangulates each from its first vertex, on the rim, into
K - 2 long thin faces whose boxes each hold the side faces along an arc of the rim (a search
that prunes faces sharing no vertex by their boxes alone is quadratic).
gear-prism K: a prism of height 1 over a K-point star (a gear's outline: radii alternating 1
and 1/2, K even), its caps fanned from their centres: the side faces run nearly radially, so
their boxes hold cap faces of a wide arc, and every cap face holds the centre (a search that
separates faces from its tree's slab volumes by their own axes alone is quadratic).
gear-dome K: the same with the caps' centres lifted 0.3 out of the caps' planes.
Used by vobb-bench-self-intersections.
Usage: fan_meshes.py double-cone|crowded-edge|spikes|rim-fan-cylinder|gear-prism|gear-dome K OUT.off
"""
import math
import random
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


def spikes(k):
    rng = random.Random(1)
    verts, faces = [], []
    for _ in range(k):
        z = rng.uniform(-1, 1)
        t = rng.uniform(0, 2 * math.pi)
        r = math.sqrt(1 - z * z)
        d = (r * math.cos(t), r * math.sin(t), z)
        a = (1.0, 0.0, 0.0) if abs(d[0]) < 0.9 else (0.0, 1.0, 0.0)
        u = cross(d, a)
        n = math.sqrt(sum(c * c for c in u))
        u = tuple(c / n for c in u)
        v = cross(d, u)
        w = 0.01  # the base's radius
        b = len(verts)
        verts.append(d)
        for j in range(3):
            c, s = math.cos(2 * math.pi * j / 3), math.sin(2 * math.pi * j / 3)
            verts.append(tuple(-d[i] + w * (c * u[i] + s * v[i]) for i in range(3)))
        faces += [(b, b + 1, b + 2), (b, b + 2, b + 3), (b, b + 3, b + 1), (b + 1, b + 3, b + 2)]
    return verts, faces


def rim_fan_cylinder(k):
    ring = [(math.cos(2 * math.pi * i / k), math.sin(2 * math.pi * i / k)) for i in range(k)]
    verts = [(x, y, 0.0) for x, y in ring] + [(x, y, 1.0) for x, y in ring]
    faces = [(i, (i + 1) % k, k + (i + 1) % k, k + i) for i in range(k)]
    faces.append(tuple(reversed(range(k))))  # bottom, facing down
    faces.append(tuple(range(k, 2 * k)))
    return verts, faces


def gear_prism(k, lift=0.0):
    verts = [(0.0, 0.0, 1.0 + lift), (0.0, 0.0, -lift)]
    for i in range(k):
        t = 2 * math.pi * i / k
        r = 1.0 if i % 2 == 0 else 0.5
        verts += [(r * math.cos(t), r * math.sin(t), 1.0), (r * math.cos(t), r * math.sin(t), 0.0)]
    faces = []
    for i in range(k):
        a, c = 2 + 2 * i, 3 + 2 * i
        b, d = 2 + 2 * ((i + 1) % k), 3 + 2 * ((i + 1) % k)
        faces += [(0, a, b), (1, d, c), (a, c, d), (a, d, b)]
    return verts, faces


def cross(p, q):
    return (p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0])


def main():
    shapes = {"double-cone": double_cone, "crowded-edge": crowded_edge, "spikes": spikes,
              "rim-fan-cylinder": rim_fan_cylinder, "gear-prism": gear_prism,
              "gear-dome": lambda k: gear_prism(k, 0.3)}
    if len(sys.argv) != 4 or sys.argv[1] not in shapes:
        sys.exit(__doc__)
    verts, faces = shapes[sys.argv[1]](int(sys.argv[2]))
    with open(sys.argv[3], "w") as f:
        f.write(f"OFF\n{len(verts)} {len(faces)} 0\n")
        f.writelines("%.17g %.17g %.17g\n" % v for v in verts)
        f.writelines("%d %s\n" % (len(p), " ".join(map(str, p))) for p in faces)


if __name__ == "__main__":
    main()

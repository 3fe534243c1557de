#!/usr/bin/env python3
"""Surface cover of a tree, per level: the mean number of level-l boxes that contain a point
drawn uniformly (by area) from the mesh's surface. A point on the surface lies in at least one
box of every layer (its own face's), so the cover is >= 1; what exceeds 1 is surface shared by
overlapping boxes. A collider resting on the surface opens every box that holds its contact
point, so the static scene's box tests at level l + 1 grow with the cover at level l (times the
arity), whatever the boxes' outer volume.

Usage: surface_cover.py MESH.off TREE.json [TREE.json ...] [--samples N] [--seed S]
"""
import argparse
import bisect
import json
import random


def read_off(path):
    """OFF or COFF (per-vertex colours after x y z are ignored), triangles only."""
    with open(path) as f:
        lines = [line.split("#")[0].split() for line in f]
    lines = [line for line in lines if line]
    if lines[0][0] not in ("OFF", "COFF"):
        raise SystemExit(f"{path}: not an OFF file")
    counts = lines[0][1:] if len(lines[0]) > 1 else lines[1]
    body = lines[1:] if len(lines[0]) > 1 else lines[2:]
    nv, nf = int(counts[0]), int(counts[1])
    verts = [tuple(float(x) for x in line[:3]) for line in body[:nv]]
    faces = []
    for line in body[nv:nv + nf]:
        if int(line[0]) != 3:
            raise SystemExit(f"{path}: a face with {line[0]} corners")
        faces.append(tuple(int(x) for x in line[1:4]))
    return verts, faces


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def area(a, b, c):
    u, v = sub(b, a), sub(c, a)
    x = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return 0.5 * (x[0] ** 2 + x[1] ** 2 + x[2] ** 2) ** 0.5


def samples(verts, faces, n, seed):
    rng = random.Random(seed)
    cumulative, total = [], 0.0
    for f in faces:
        total += area(*(verts[i] for i in f))
        cumulative.append(total)
    points = []
    for _ in range(n):
        f = faces[min(bisect.bisect_left(cumulative, rng.random() * total), len(faces) - 1)]
        a, b, c = (verts[i] for i in f)
        s, t = rng.random(), rng.random()
        if s + t > 1:
            s, t = 1 - s, 1 - t
        points.append(tuple(a[k] + s * (b[k] - a[k]) + t * (c[k] - a[k]) for k in range(3)))
    return points


def inside(box, p):
    d = sub(p, box["center"])
    # A relative slack of 1e-9 keeps points on a face of their own box inside (the boxes are
    # fitted to the faces, so surface points can lie exactly on a box face).
    return all(abs(sum(d[k] * axis[k] for k in range(3))) <= h * (1 + 1e-9) + 1e-12
               for axis, h in zip(box["axes"], box["half_extents"]))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("mesh")
    parser.add_argument("trees", nargs="+")
    parser.add_argument("--samples", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    verts, faces = read_off(args.mesh)
    points = samples(verts, faces, args.samples, args.seed)
    for path in args.trees:
        with open(path) as f:
            tree = json.load(f)
        nodes = {n["id"]: n for n in tree["nodes"]}
        # Layer l: the nodes at level l, and the leaves above it.
        layers = []
        for level in range(tree["depth"] + 1):
            layers.append([n for n in nodes.values()
                           if n["level"] == level or (n["level"] < level and not n["children"])])
        covers = []
        for layer in layers:
            count = 0
            for p in points:
                count += sum(1 for n in layer if inside(n, p))
            covers.append(count / len(points))
        print(f"{path} ({tree['method']}): " + " ".join(f"{c:.3f}" for c in covers))


if __name__ == "__main__":
    main()

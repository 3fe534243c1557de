#!/usr/bin/env python3
"""Regenerates the bad-input corpus (committed; run by hand after a change).

Each file shows one defect; EXPECTED.tsv names the phrase that vobb's one-line error must
contain for it. The test (tests/app/cli_test.cpp) runs `vobb info` and `vobb build` on each.
"""
import random, struct

# Unit cube, corners by bit (x = bit 0, y = bit 1, z = bit 2), quads outward.
V = [(i & 1, (i >> 1) & 1, (i >> 2) & 1) for i in range(8)]
Q = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
F = [t for a, b, c, d in Q for t in ((a, b, c), (a, c, d))]

def off(verts, faces, header="OFF"):
    s = f"{header}\n{len(verts)} {len(faces)} 0\n"
    s += "".join(" ".join(str(x) for x in v) + "\n" for v in verts)
    s += "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)
    return s

def shifted(verts, d):
    return [tuple(x + e for x, e in zip(v, d)) for v in verts]

def two_cubes(offset):
    verts = V + shifted(V, offset)
    faces = F + [tuple(i + 8 for i in f) for f in F]
    return verts, faces

files = {}
files["empty.off"] = ""
files["truncated_vertices.off"] = off(V, F).split("\n", 7)
files["truncated_vertices.off"] = "\n".join(off(V, F).split("\n")[:7]) + "\n"
files["truncated_faces.off"] = "\n".join(off(V, F).split("\n")[:15]) + "\n"
files["faces_beyond_count.off"] = off(V, F).replace("8 12 0", "8 10 0", 1)
nanv = list(V); nanv[3] = (1, "nan", 0)
files["nan_coordinate.off"] = off(nanv, F)
files["inf_coordinate.obj"] = "".join(f"v {x} {y} {z}\n" for x, y, z in V[:5]) + "v 1 inf 1\n" + \
    "".join(f"v {x} {y} {z}\n" for x, y, z in V[6:]) + "".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in F)
files["open_cube.off"] = off(V, F[:-1])
v2, f2 = two_cubes((1, 1, 0))
files["nonmanifold_edge.off"] = off(v2, f2)
v4, f4 = two_cubes((1, 1, 1))
files["nonmanifold_vertex.off"] = off(v4, f4)
flipped = list(F); flipped[5] = flipped[5][::-1]
files["flipped_face.off"] = off(V, flipped)
files["inward.off"] = off(V, [f[::-1] for f in F])
v3, f3 = two_cubes((0.5, 0.5, 0.5))
files["self_intersecting.off"] = off(v3, f3)
files["degenerate_collinear_face.off"] = off(V + [(0.5, 0, 0)], F + [(0, 1, 8)])
files["repeated_index.obj"] = "".join(f"v {x} {y} {z}\n" for x, y, z in V) + \
    "".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in F) + "f 1 1 2\n"
files["index_out_of_range.off"] = off(V, F[:-1] + [(4, 5, 99)])
files["zero_index.obj"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"
files["index_out_of_range.obj"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 9\n"
files["not_a_number.obj"] = "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"
files["huge_count.off"] = "OFF\n1000000000000000 12 0\n0 0 0\n"
files["negative_count.off"] = "OFF\n-8 12 0\n"
files["bad_edge_count.off"] = off(V, F).replace("\n8 12 0\n", "\n8 12 x\n", 1)
files["not_off_header.off"] = "PLY\n8 12 0\n"
cav_v = [tuple(4 * x for x in v) for v in V] + [tuple(1 + 2 * x for x in v) for v in V]
cav_f = F + [tuple(i + 8 for i in f) for f in F]  # cavity facing out: wrong
files["cavity_facing_out.off"] = off(cav_v, cav_f)
files["huge_coordinates.off"] = off([(0, 0, 0), (1e308, 0, 0), (0, 1e308, 0), (0, 0, 1e308)],
                                    [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])
files["duplicate_faces.off"] = off(V, F + [F[0], F[0][::-1], F[7]])
files["tiny_extent.off"] = off([tuple(1e-80 * x for x in v) for v in V], F)
files["lines_only.obj"] = "v 0 0 0\nv 1 0 0\nl 1 2\n"
files["no_faces.stl"] = "solid empty\nendsolid empty\n"
files["bad_ply_header.ply"] = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nend_header\n"
# Binary ones.
rnd = random.Random(20261121)
garbage = bytes(rnd.randrange(256) for _ in range(777))
files["binary_garbage.off"] = garbage
files["binary_garbage.stl"] = garbage
stl = b"\0" * 80 + struct.pack("<I", 12)
for a, b, c in F:
    stl += struct.pack("<3f", 0, 0, 0)
    for i in (a, b, c):
        stl += struct.pack("<3f", *V[i])
    stl += b"\0\0"
files["truncated_binary.stl"] = stl[: len(stl) - 70]
ply = ("ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty double x\nproperty double y\n"
       "property double z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n").encode()
for v in V:
    ply += struct.pack("<3d", *v)
for f in F:
    ply += struct.pack("<B3i", 3, *f)
files["truncated_binary.ply"] = ply[: len(ply) - 9]
files["cr_line_ends.off"] = off(V, F).replace("\n", "\r")
files["relative_index_before_first.obj"] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"
# A signed list length of -1 in the first face record (binary: no line to name).
files["bad_list_length_binary.ply"] = ply.replace(b"property list uchar int", b"property list char int").replace(
    struct.pack("<B3i", 3, *F[0]), struct.pack("<b3i", -1, *F[0]), 1)
# Headers that undercount: the records beyond the count would be a hole if dropped.
files["records_beyond_count.stl"] = stl[:80] + struct.pack("<I", 10) + stl[84:]
files["records_beyond_count_binary.ply"] = ply.replace(b"element face 12", b"element face 10")
files["records_beyond_count.ply"] = (
    "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 10\nproperty list uchar int vertex_indices\nend_header\n" +
    "".join(" ".join(map(str, v)) + "\n" for v in V) + "".join("3 %d %d %d\n" % f for f in F))

# Words where OFF allows only numbers (a colour after a face's indices, a normal or colour
# after a vertex's coordinates), and more values after the indices than a colour holds.
files["junk_after_face_indices.off"] = off(V, F).replace("3 0 4 6\n", "3 0 4 6 abc\n", 1)
files["one_line.off"] = " ".join(off(V, F).split()) + "\n"
files["two_vertices_on_a_line.off"] = off(V, F).replace("\n1 0 0\n0 1 0\n", "\n1 0 0 0 1 0\n", 1)
files["junk_after_vertex.off"] = off(V, F).replace("\n1 0 0\n", "\n1 0 0 zz\n", 1)
files["long_face_line.off"] = off(V, F).replace("3 0 4 6\n", "3 0 4 6 1 2 3 4 5\n", 1)
# ASCII PLY and OBJ records with more than they should hold: a word after a vertex, a face
# line with one index more than its list length says, a word after an OBJ vertex.
ply_ascii = ("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 12\nproperty list uchar int vertex_indices\nend_header\n" +
             "".join(" ".join(map(str, v)) + "\n" for v in V) + "".join("3 %d %d %d\n" % f for f in F))
files["junk_after_vertex.ply"] = ply_ascii.replace("\n1 0 0\n", "\n1 0 0 zz\n", 1)
files["index_beyond_list_length.ply"] = ply_ascii.replace("3 %d %d %d\n" % F[0], "3 %d %d %d 7\n" % F[0], 1)
files["junk_after_vertex.obj"] = ("".join("v %d %d %d\n" % v for v in V).replace("v 1 0 0\n", "v 1 0 0 zz\n", 1) +
                                  "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in F))
# ASCII STL out of its grammar: a facet without its outer loop, words after a vertex's
# coordinates, and text after endsolid.
def stl_ascii(facets):
    s = "solid cube\n"
    for tri in facets:
        s += "facet normal 0 0 0\nouter loop\n" + "".join("vertex %d %d %d\n" % V[i] for i in tri)
        s += "endloop\nendfacet\n"
    return s + "endsolid cube\n"
files["facet_without_loop.stl"] = stl_ascii(F).replace("outer loop\n", "", 1).replace("endloop\n", "", 1)
files["junk_after_vertex.stl"] = stl_ascii(F).replace("vertex 0 0 0\n", "vertex 0 0 0 7\n", 1)
files["text_after_endsolid.stl"] = stl_ascii(F) + "facet normal 0 0 0\n"
files["facet_normal_words.stl"] = stl_ascii(F).replace("facet normal 0 0 0\n", "facet normal a b c\n", 1)

for name, content in files.items():
    with open(name, "wb") as fh:
        fh.write(content.encode() if isinstance(content, str) else content)

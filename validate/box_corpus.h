// Seeded corpora of boxes over a mesh, in the three sizes that the estimator's accuracy is
// reported for (DESIGN §4): leaf-sized, mid-level and root-sized.
//
// Each box is a node box of the mesh's OBB-Tree baseline (levels 8, 4 and 0, or the deepest
// level the tree has), chosen at random and then jittered: the centre moves by up to 25 % of
// each half extent along each axis, the axes turn by up to 15 degrees about a random axis, and
// each half extent is scaled by a factor in [0.8, 1.25]. So the boxes have the sizes and the
// surface contact of real tree boxes, with centres both inside and outside the solid.
// The same (mesh, size, count, seed) gives the same boxes on every machine: the generator is
// std::mt19937_64 with its output mapped to doubles by hand (no std distributions).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/mesh.h"
#include "common/obb.h"

namespace vobb::validate {

enum class BoxSize { kLeaf, kMid, kRoot };
const char* to_string(BoxSize s);
int tree_level(BoxSize s);  // 8, 4, 0

std::vector<Obb> box_corpus(const Mesh& mesh, BoxSize size, int count, uint64_t seed);

}  // namespace vobb::validate

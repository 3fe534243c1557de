// Tree and box files (DESIGN §7), as JSON.
//
// Tree: {"format":"vobb-tree","version":1,"mesh":{"triangles","sha256"},"method","arity",
//        "depth","nodes":[{"id","parent","level","center","axes","half_extents","children",
//        "faces"}]}, axes[k] being axis k in world coordinates.
// Boxes: {"boxes":[{"center","axes","half_extents"}, ...]}.
// Readers ignore keys they do not know. Doubles are written with digits that read back to the
// same double (nlohmann's Grisu2: at most 17 significant digits, nearly always the fewest), so
// a tree survives write + read bit for bit, and the same tree gives the same bytes.
// Writes are atomic (temp file + rename).
#pragma once

#include <string>
#include <vector>

#include "common/obb.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb {

std::string tree_to_json(const Tree& tree);
// Refuses, writing nothing, a tree validate_tree refuses or with a box box_defect refuses: no
// file its reader would refuse.
Status write_tree(const Tree& tree, const std::string& path);
// Parses and validates (validate_tree). An inner node without "faces" gets its children's.
Status read_tree(const std::string& path, Tree* tree);
Status parse_tree(const std::string& text, const std::string& display, Tree* tree);

// Refuses, writing nothing, a box box_defect refuses.
Status write_boxes(const std::vector<Obb>& boxes, const std::string& path);
Status read_boxes(const std::string& path, std::vector<Obb>* boxes);

}  // namespace vobb

// Writes boxes as a polygon mesh for viewing (MeshLab, Blender): 8 corners and 6 outward
// quads per box. The format follows the extension: .obj (one object per box, named as the
// caller names it, else "box_<index>"; export_layer names them "node_<id>") or .ply (ASCII).
// The file appears atomically.
#pragma once

#include <string>
#include <vector>

#include "common/obb.h"
#include "common/status.h"
#include "common/tree.h"

namespace vobb {

// Whether `path` names a format this writer knows (.obj or .ply): the command line asks before
// its run, and export_boxes again.
Status check_box_export_path(const std::string& path);

// `names` labels each box (OBJ object names); may be empty.
Status export_boxes(const std::vector<Obb>& boxes, const std::vector<std::string>& names,
                    const std::string& path);

// The boxes of layer `level` of the tree, named "node_<id>" by node id. Fails on a level outside
// [0, depth] or an unknown extension.
Status export_layer(const Tree& tree, int level, const std::string& path);

}  // namespace vobb

#include "common/box_export.h"

#include <array>

#include "common/atomic_file.h"
#include "common/text_util.h"

namespace vobb {
Status check_box_export_path(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "obj" || ext == "ply") return Status::ok();
  return Status::error(path + ": unknown box export format (use .obj or .ply)");
}

namespace {

// A box's quad k with its corners in outward order: kBoxQuads as given for right-handed axes,
// reversed for left-handed ones (a frame read from a file may be either; box_defect).
std::array<int, 4> outward_quad(const Obb& box, int k) {
  const int* q = kBoxQuads[k];
  if (box.axes[0].dot(box.axes[1].cross(box.axes[2])) >= 0) return {q[0], q[1], q[2], q[3]};
  return {q[3], q[2], q[1], q[0]};
}

}  // namespace

Status export_boxes(const std::vector<Obb>& boxes, const std::vector<std::string>& names,
                    const std::string& path) {
  Status known = check_box_export_path(path);
  if (!known) return known;
  const std::string ext = extension_of(path);
  std::string s;
  if (ext == "obj") {
    s = "# vobb boxes: " + std::to_string(boxes.size()) + "\n";
    for (size_t b = 0; b < boxes.size(); ++b) {
      s += "o " + (b < names.size() ? names[b] : "box_" + std::to_string(b)) + "\n";
      for (const Vec3& p : corners(boxes[b])) {
        s += "v ";
        append_xyz(&s, p);
        s += '\n';
      }
      for (int k = 0; k < 6; ++k) {
        s += "f";
        for (int c : outward_quad(boxes[b], k)) s += " " + std::to_string(8 * b + c + 1);
        s += '\n';
      }
    }
  } else {  // ply
    s = "ply\nformat ascii 1.0\ncomment vobb boxes\nelement vertex " +
        std::to_string(8 * boxes.size()) +
        "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
        std::to_string(6 * boxes.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Obb& box : boxes)
      for (const Vec3& p : corners(box)) {
        append_xyz(&s, p);
        s += '\n';
      }
    for (size_t b = 0; b < boxes.size(); ++b)
      for (int k = 0; k < 6; ++k) {
        s += "4";
        for (int c : outward_quad(boxes[b], k)) s += " " + std::to_string(8 * b + c);
        s += '\n';
      }
  }
  return write_file_atomic(path, s);
}

Status export_layer(const Tree& tree, int level, const std::string& path) {
  if (level < 0 || level > tree.depth)
    return Status::error("level " + std::to_string(level) + " is outside [0, " +
                         std::to_string(tree.depth) + "]");
  std::vector<Obb> boxes;
  std::vector<std::string> names;
  for (int32_t id : layer(tree, level)) {
    boxes.push_back(tree.nodes[id].box);
    names.push_back("node_" + std::to_string(id));
  }
  return export_boxes(boxes, names, path);
}

}  // namespace vobb

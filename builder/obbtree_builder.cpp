#include "builder/obbtree_builder.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <deque>
#include <numeric>

#include "common/obb.h"

namespace vobb {
namespace {

struct Moments {
  double area = 0.0;
  Vec3 first = Vec3::Zero();                         // sum A m
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // sum (A/12)(9 m m^T + p p^T + q q^T + r r^T)
};

// Moments about `origin` (the faces' box centre), which keeps far-off meshes accurate.
Moments moments(const Mesh& mesh, const std::vector<int32_t>& faces, const Vec3& origin) {
  Moments mo;
  for (int32_t f : faces) {
    const Vec3 p = mesh.corner(f, 0) - origin, q = mesh.corner(f, 1) - origin,
               r = mesh.corner(f, 2) - origin;
    const double a = 0.5 * (q - p).cross(r - p).norm();
    const Vec3 m = (p + q + r) / 3.0;
    mo.area += a;
    mo.first += a * m;
    mo.second += (a / 12.0) * (9.0 * m * m.transpose() + p * p.transpose() + q * q.transpose() +
                               r * r.transpose());
  }
  return mo;
}

Vec3 canonical_sign(Vec3 v) {
  int i;
  v.cwiseAbs().maxCoeff(&i);
  return v[i] < 0 ? Vec3(-v) : v;
}

Vec3 faces_center(const Mesh& mesh, const std::vector<int32_t>& faces) {
  Aabb b;
  for (int32_t f : faces) b.extend(mesh.face_bounds(f));
  return 0.5 * (b.lo + b.hi);
}

// Splits `faces` in two by the RAPID rule along `axis`; `mean` is the split coordinate.
void split_faces(const Mesh& mesh, const std::vector<int32_t>& faces, const Vec3& axis, double mean,
                 std::vector<int32_t>* left, std::vector<int32_t>* right) {
  std::vector<std::pair<double, int32_t>> key;
  key.reserve(faces.size());
  for (int32_t f : faces) {
    const Vec3 c = (mesh.corner(f, 0) + mesh.corner(f, 1) + mesh.corner(f, 2)) / 3.0;
    key.emplace_back(c.dot(axis), f);
  }
  left->clear();
  right->clear();
  for (const auto& [s, f] : key) (s < mean ? left : right)->push_back(f);
  if (left->empty() || right->empty()) {
    // Median fallback: order by projection, ties by face id.
    std::sort(key.begin(), key.end());
    left->clear();
    right->clear();
    const size_t half = key.size() / 2;
    for (size_t i = 0; i < key.size(); ++i) (i < half ? left : right)->push_back(key[i].second);
    std::sort(left->begin(), left->end());
    std::sort(right->begin(), right->end());
  }
}

void split_by_rapid_rule(const Mesh& mesh, const std::vector<int32_t>& faces,
                         std::vector<int32_t>* left, std::vector<int32_t>* right) {
  const Vec3 origin = faces_center(mesh, faces);
  const Moments mo = moments(mesh, faces, origin);
  const std::array<Vec3, 3> axes = covariance_axes(mesh, faces);
  const Vec3 mean = origin + mo.first / mo.area;
  split_faces(mesh, faces, axes[0], mean.dot(axes[0]), left, right);
}

}  // namespace

std::array<Vec3, 3> covariance_axes(const Mesh& mesh, const std::vector<int32_t>& faces) {
  const Vec3 origin = faces_center(mesh, faces);
  const Moments mo = moments(mesh, faces, origin);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
  if (mo.area > 0) {
    const Vec3 mu = mo.first / mo.area;
    cov = mo.second / mo.area - mu * mu.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  // Eigen sorts eigenvalues ascending: the major axis is the last column.
  const Vec3 a0 = canonical_sign(eig.eigenvectors().col(2));
  Vec3 a1 = eig.eigenvectors().col(1);
  a1 = canonical_sign((a1 - a1.dot(a0) * a0).normalized());
  return orthonormalize({a0, a1, a0.cross(a1)});
}

std::vector<std::vector<int32_t>> split_into_groups(const Mesh& mesh,
                                                    const std::vector<int32_t>& faces, int arity) {
  std::vector<std::vector<int32_t>> groups{faces};
  while (static_cast<int>(groups.size()) < arity) {
    // The largest group with more than one face; the first on ties.
    size_t best = groups.size();
    for (size_t g = 0; g < groups.size(); ++g)
      if (groups[g].size() > 1 && (best == groups.size() || groups[g].size() > groups[best].size()))
        best = g;
    if (best == groups.size()) break;
    std::vector<int32_t> left, right;
    split_by_rapid_rule(mesh, groups[best], &left, &right);
    groups[best] = std::move(left);
    groups.insert(groups.begin() + best + 1, std::move(right));
  }
  return groups;
}

Tree build_obbtree(const Mesh& mesh, const ObbTreeOptions& options) {
  VOBB_ASSERT(options.depth >= 0 && options.arity >= 2, "depth >= 0 and arity >= 2");
  VOBB_ASSERT(!mesh.faces.empty(), "build_obbtree needs faces");
  Tree tree;
  tree.method = "obbtree";
  tree.arity = options.arity;
  tree.mesh_triangles = mesh.faces.size();
  TreeNode root;
  root.faces.resize(mesh.faces.size());
  std::iota(root.faces.begin(), root.faces.end(), 0);
  tree.nodes.push_back(root);
  // Breadth first: ids grow level by level, children after their parent.
  for (size_t i = 0; i < tree.nodes.size(); ++i) {
    TreeNode& node = tree.nodes[i];
    node.box = fit_obb(mesh, node.faces, covariance_axes(mesh, node.faces));
    tree.depth = std::max(tree.depth, static_cast<int>(node.level));
    if (node.level >= options.depth || node.faces.size() < 2) continue;
    std::vector<std::vector<int32_t>> groups = split_into_groups(mesh, node.faces, options.arity);
    const int32_t parent = static_cast<int32_t>(i);
    const int32_t level = node.level + 1;
    for (auto& g : groups) {
      TreeNode child;
      child.id = static_cast<int32_t>(tree.nodes.size());
      child.parent = parent;
      child.level = level;
      child.faces = std::move(g);
      tree.nodes[parent].children.push_back(child.id);
      tree.nodes.push_back(std::move(child));  // invalidates `node`; not used below
    }
  }
  return tree;
}

}  // namespace vobb

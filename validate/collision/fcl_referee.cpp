#include "validate/collision/fcl_referee.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBB.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>
#include <fcl/narrowphase/detail/gjk_solver_libccd.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_shape_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <algorithm>
#include <limits>

namespace vobb::collision {
namespace {

using FclObb = fcl::OBB<double>;
using Model = fcl::BVHModel<FclObb>;
using Solver = fcl::detail::GJKSolver_libccd<double>;

// One node of our tree binarised for FCL, in the pre-order in which FCL builds its nodes.
struct PlanNode {
  Obb box;
  std::vector<uint32_t> faces;  // ascending
  int left = -1, right = -1;
  int32_t ours = -1;  // our node id, or -1 for a padding node
};

class Plan {
 public:
  Plan(const Tree& tree) : tree_(tree) {}
  bool build() { return expand_node(0) >= 0; }
  const std::vector<PlanNode>& nodes() const { return nodes_; }

 private:
  int add(const Obb& box, int32_t ours, std::vector<uint32_t> faces) {
    std::sort(faces.begin(), faces.end());
    nodes_.push_back({box, std::move(faces), -1, -1, ours});
    return static_cast<int>(nodes_.size()) - 1;
  }
  int expand_node(int32_t id) {
    const TreeNode& t = tree_.nodes[id];
    if (t.is_leaf())
      return expand_faces(t.box, id, std::vector<uint32_t>(t.faces.begin(), t.faces.end()));
    if (t.children.size() < 2) return -1;
    return expand_children(t.box, id, t.children);
  }
  int expand_children(const Obb& box, int32_t ours, const std::vector<int32_t>& kids) {
    std::vector<uint32_t> faces;
    for (int32_t k : kids)
      faces.insert(faces.end(), tree_.nodes[k].faces.begin(), tree_.nodes[k].faces.end());
    const int idx = add(box, ours, std::move(faces));
    const int l = expand_node(kids[0]);
    const int r =
        kids.size() == 2
            ? expand_node(kids[1])
            : expand_children(box, -1, std::vector<int32_t>(kids.begin() + 1, kids.end()));
    if (l < 0 || r < 0) return -1;
    nodes_[idx].left = l;
    nodes_[idx].right = r;
    return idx;
  }
  int expand_faces(const Obb& box, int32_t ours, const std::vector<uint32_t>& faces) {
    const int idx = add(box, ours, faces);
    if (faces.size() == 1) return idx;
    const size_t half = faces.size() / 2;
    const int l = expand_faces(box, -1, std::vector<uint32_t>(faces.begin(), faces.begin() + half));
    const int r = expand_faces(box, -1, std::vector<uint32_t>(faces.begin() + half, faces.end()));
    nodes_[idx].left = l;
    nodes_[idx].right = r;
    return idx;
  }
  const Tree& tree_;
  std::vector<PlanNode> nodes_;
};

FclObb to_fcl(const Obb& b) {
  FclObb o;
  for (int k = 0; k < 3; ++k) o.axis.col(k) = b.axes[k];
  o.To = b.center;
  o.extent = b.half;
  return o;
}

// FCL's build calls fit() then computeRule() once per node, in pre-order, and then apply()
// once per primitive of the node, in the order of the primitive array that computeRule saw
// (BVHModel::recursiveBuildTree in FCL 0.7: the swap loop visits index i while it still holds
// its original entry). A shared cursor ties the three calls to the plan node being built.
struct BuildState {
  const std::vector<PlanNode>* plan = nullptr;
  size_t cursor = 0;
  bool ok = true;
};

class PlanFitter : public fcl::detail::BVFitterBase<FclObb> {
 public:
  explicit PlanFitter(BuildState* s) : s_(s) {}
  void set(fcl::Vector3<double>*, fcl::Triangle*, fcl::BVHModelType) override {}
  void set(fcl::Vector3<double>*, fcl::Vector3<double>*, fcl::Triangle*,
           fcl::BVHModelType) override {}
  FclObb fit(unsigned int* primitives, int n) override {
    const std::vector<PlanNode>& plan = *s_->plan;
    if (s_->cursor >= plan.size()) {
      s_->ok = false;
      return FclObb();
    }
    const PlanNode& node = plan[s_->cursor++];
    std::vector<uint32_t> got(primitives, primitives + n);
    std::sort(got.begin(), got.end());
    if (got != node.faces) s_->ok = false;
    return to_fcl(node.box);
  }
  void clear() override {}

 private:
  BuildState* s_;
};

class PlanSplitter : public fcl::detail::BVSplitterBase<FclObb> {
 public:
  explicit PlanSplitter(BuildState* s) : s_(s) {}
  void set(fcl::Vector3<double>*, fcl::Triangle*, fcl::BVHModelType) override {}
  void computeRule(const FclObb&, unsigned int* primitives, int n) override {
    right_.assign(n, false);
    next_ = 0;
    const std::vector<PlanNode>& plan = *s_->plan;
    const PlanNode& node = plan[s_->cursor - 1];
    if (node.left < 0) return;
    const std::vector<uint32_t>& left = plan[node.left].faces;
    for (int i = 0; i < n; ++i)
      right_[i] = !std::binary_search(left.begin(), left.end(), primitives[i]);
  }
  bool apply(const fcl::Vector3<double>&) const override {
    if (next_ >= right_.size()) return true;
    return right_[next_++];
  }
  void clear() override {}

 private:
  BuildState* s_;
  std::vector<bool> right_;
  mutable size_t next_ = 0;
};

// FCL's OBB mesh–shape traversal node, with a tally of the BV tests on our tree's nodes.
template <class Shape>
class CountingNode : public fcl::detail::MeshShapeCollisionTraversalNodeOBB<Shape, Solver> {
 public:
  using Base = fcl::detail::MeshShapeCollisionTraversalNodeOBB<Shape, Solver>;
  bool BVTesting(int b1, int b2) const override {
    if (ours_ == nullptr || (*ours_)[b1]) ++tree_node_tests_;
    return Base::BVTesting(b1, b2);
  }
  const std::vector<char>* ours_ = nullptr;
  mutable uint64_t tree_node_tests_ = 0;
};

std::shared_ptr<Model> new_model(const Mesh& mesh) {
  auto model = std::make_shared<Model>();
  std::vector<fcl::Vector3<double>> vertices(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) triangles.emplace_back(f[0], f[1], f[2]);
  model->beginModel();
  model->addSubModel(vertices, triangles);
  return model;
}

}  // namespace

struct FclModel::Impl {
  std::shared_ptr<Model> model;
  std::vector<char> ours;  // per FCL BV index: is it one of our tree's nodes (empty: fcl_own)
  Solver solver;

  template <class Shape>
  FclQueryResult run(const Shape& shape, const fcl::Transform3<double>& tf2) const {
    CountingNode<Shape> node;
    node.ours_ = ours.empty() ? nullptr : &ours;
    fcl::CollisionRequest<double> request(std::numeric_limits<size_t>::max(), false);
    fcl::CollisionResult<double> result;
    const fcl::Transform3<double> tf1 = fcl::Transform3<double>::Identity();
    fcl::detail::initialize(node, *model, tf1, shape, tf2, &solver, request, result);
    node.enableStatistics(true);
    fcl::detail::collide(&node);
    FclQueryResult r;
    r.collide = result.isCollision();
    for (size_t i = 0; i < result.numContacts(); ++i) r.faces.push_back(result.getContact(i).b1);
    std::sort(r.faces.begin(), r.faces.end());
    r.faces.erase(std::unique(r.faces.begin(), r.faces.end()), r.faces.end());
    r.bv_tests = static_cast<uint64_t>(node.num_bv_tests);
    r.leaf_tests = static_cast<uint64_t>(node.num_leaf_tests);
    r.tree_node_bv_tests = node.tree_node_tests_;
    return r;
  }
};

FclModel::FclModel(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FclModel::~FclModel() = default;

std::unique_ptr<FclModel> FclModel::fcl_own(const Mesh& mesh) {
  auto impl = std::make_unique<Impl>();
  impl->model = new_model(mesh);
  impl->model->endModel();
  return std::unique_ptr<FclModel>(new FclModel(std::move(impl)));
}

Status FclModel::from_tree(const Mesh& mesh, const Tree& tree, const std::string& display,
                           std::unique_ptr<FclModel>* out) {
  Plan plan(tree);
  if (!plan.build())
    return Status::error(display + ": a node has a single child; FCL's binary BVH cannot hold it");
  BuildState state;
  state.plan = &plan.nodes();
  auto impl = std::make_unique<Impl>();
  impl->model = new_model(mesh);
  impl->model->bv_fitter = std::make_shared<PlanFitter>(&state);
  impl->model->bv_splitter = std::make_shared<PlanSplitter>(&state);
  impl->model->endModel();
  const Model& m = *impl->model;
  if (!state.ok || state.cursor != plan.nodes().size() ||
      m.getNumBVs() != static_cast<int>(plan.nodes().size()))
    return Status::error(display + ": FCL's build did not follow the tree's partition");
  // Walk FCL's nodes in pre-order beside the plan: same boxes, same leaf faces.
  impl->ours.assign(m.getNumBVs(), 0);
  size_t k = 0;
  bool same = true;
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const int b = stack.back();
    stack.pop_back();
    const PlanNode& p = plan.nodes()[k++];
    const fcl::BVNode<FclObb>& n = m.getBV(b);
    const FclObb want = to_fcl(p.box);
    same = same && n.bv.To == want.To && n.bv.extent == want.extent && n.bv.axis == want.axis;
    same = same && (n.isLeaf() == (p.left < 0));
    if (n.isLeaf()) {
      same = same && p.faces.size() == 1 && static_cast<uint32_t>(n.primitiveId()) == p.faces[0];
    } else {
      stack.push_back(n.rightChild());
      stack.push_back(n.leftChild());
    }
    impl->ours[b] = p.ours >= 0;
  }
  if (!same) return Status::error(display + ": FCL's model differs from the tree (boxes or faces)");
  *out = std::unique_ptr<FclModel>(new FclModel(std::move(impl)));
  return Status::ok();
}

FclQueryResult FclModel::query(const Collider& c) const {
  fcl::Transform3<double> tf2 = fcl::Transform3<double>::Identity();
  tf2.translation() = c.center;
  if (c.shape == ColliderShape::kSphere) return impl_->run(fcl::Sphere<double>(c.radius), tf2);
  for (int k = 0; k < 3; ++k) tf2.linear().col(k) = c.axes[k];
  return impl_->run(fcl::Box<double>(2 * c.half[0], 2 * c.half[1], 2 * c.half[2]), tf2);
}

size_t FclModel::bv_count() const { return static_cast<size_t>(impl_->model->getNumBVs()); }

}  // namespace vobb::collision

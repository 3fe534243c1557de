#include "validate/collision/collision_experiment.h"

#include <ode/ode.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>

#include "collision/contact_predicates.h"
#include "validate/collision/fcl_referee.h"

namespace vobb::collision {
namespace {

using Clock = std::chrono::steady_clock;

// Portable uniform numbers from a fixed engine (the standard distributions are not specified
// bit for bit across library versions).
class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  Eigen::Matrix3d rotation() {  // uniform on SO(3) (Shoemake)
    const double u1 = uniform(), u2 = 2 * M_PI * uniform(), u3 = 2 * M_PI * uniform();
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2),
                              b * std::sin(u3))
        .normalized()
        .toRotationMatrix();
  }

 private:
  std::mt19937_64 engine_;
};

// Collider sizes, as fractions of the model's bounding radius R (times collider_scale).
constexpr double kSphereRadius[2] = {0.02, 0.08};
constexpr double kBoxHalf[2] = {0.015, 0.06};

// `unit` is R times collider_scale. It scales the sizes only, so the random draws are the
// same for every scale.
Collider random_collider(Random& rng, double unit, const Vec3& center, const Eigen::Matrix3d& rot) {
  Collider c;
  c.center = center;
  if (rng.uniform() < 0.5) {
    c.shape = ColliderShape::kSphere;
    c.radius = unit * rng.uniform(kSphereRadius[0], kSphereRadius[1]);
  } else {
    c.shape = ColliderShape::kBox;
    for (int k = 0; k < 3; ++k) {
      c.half[k] = unit * rng.uniform(kBoxHalf[0], kBoxHalf[1]);
      c.axes[k] = rot.col(k);
    }
  }
  return c;
}

// Runs brute force, every tree and FCL on each query, and keeps the tallies.
class QueryEngine {
 public:
  QueryEngine(const Mesh& mesh, const std::vector<NamedTree>& trees, const ExperimentOptions& opt,
              ExperimentReport* report)
      : mesh_(mesh),
        scale_(mesh_scale(mesh)),
        report_(report),
        tamper_(opt.tamper_answer),
        on_query_(opt.on_query),
        brute_force_(mesh) {
    for (const NamedTree& t : trees) traversals_.emplace_back(mesh, *t.tree);
    if (opt.fcl) {
      fcl_own_ = FclModel::fcl_own(mesh);
      report_->fcl_own.available = true;
      for (size_t i = 0; i < trees.size(); ++i) {
        std::unique_ptr<FclModel> m;
        const Status s = FclModel::from_tree(mesh, *trees[i].tree, trees[i].name, &m);
        report_->trees[i].fcl.available = static_cast<bool>(s);
        if (!s) report_->trees[i].fcl.note = s.message();
        fcl_trees_.push_back(std::move(m));
      }
    } else {
      fcl_trees_.resize(trees.size());
    }
  }

  // One query; returns brute force's touching faces.
  const std::vector<int32_t>& query(const Collider& c) {
    if (on_query_) on_query_(c);
    const PreparedCollider pc = prepare_collider(c, scale_);
    ++report_->queries;
    const auto t0 = Clock::now();
    brute_force_.touching(pc, &brute_);
    report_->brute_force_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    if (!brute_.empty()) ++report_->touching_queries;
    for (size_t i = 0; i < traversals_.size(); ++i) {
      TreeResult& tr = report_->trees[i];
      const auto t1 = Clock::now();
      traversals_[i].query(pc, &faces_, &tr.counts);
      tr.narrow_phase_seconds += std::chrono::duration<double>(Clock::now() - t1).count();
      if (tamper_) tamper_(i, report_->queries, &faces_);
      if (faces_ != brute_) {
        ++tr.disagreements;
        if (report_->brute_force_agrees) {
          report_->brute_force_agrees = false;
          report_->first_disagreement = tr.name + ": query " + std::to_string(report_->queries) +
                                        " found " + std::to_string(faces_.size()) +
                                        " touching faces, brute force " +
                                        std::to_string(brute_.size());
        }
      }
      if (fcl_trees_[i]) tally(fcl_trees_[i]->query(c), &tr.fcl);
    }
    if (fcl_own_) tally(fcl_own_->query(c), &report_->fcl_own);
    return brute_;
  }

  const Mesh& mesh() const { return mesh_; }

 private:
  void tally(const FclQueryResult& r, FclCounts* out) const {
    out->bv_tests += r.bv_tests;
    out->leaf_tests += r.leaf_tests;
    out->tree_node_bv_tests += r.tree_node_bv_tests;
    if (r.collide != !brute_.empty()) ++out->answer_disagreements;
    if (r.faces != brute_) ++out->face_disagreements;
  }

  const Mesh& mesh_;
  const double scale_;
  ExperimentReport* report_;
  const std::function<void(size_t, uint64_t, std::vector<int32_t>*)> tamper_;
  const std::function<void(const Collider&)> on_query_;
  const BruteForce brute_force_;
  std::vector<TreeTraversal> traversals_;
  std::unique_ptr<FclModel> fcl_own_;
  std::vector<std::unique_ptr<FclModel>> fcl_trees_;
  std::vector<int32_t> brute_, faces_;
};

// ---- static mode ---------------------------------------------------------------------------

void run_static(QueryEngine& engine, const Tree& first, const ExperimentOptions& opt) {
  const Mesh& mesh = engine.mesh();
  Random rng(opt.seed);
  std::vector<double> cumulative(mesh.faces.size());
  double total = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    cumulative[f] = (total += 0.5 * mesh.double_area(f));
  const Obb& root = first.nodes[0].box;
  const double R = root.half.norm();
  for (int q = 0; q < opt.colliders; ++q) {
    const size_t f = std::min<size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), rng.uniform() * total) -
            cumulative.begin(),
        mesh.faces.size() - 1);
    double s = rng.uniform(), t = rng.uniform();
    if (s + t > 1) s = 1 - s, t = 1 - t;
    const Vec3 a = mesh.corner(f, 0), b = mesh.corner(f, 1), c = mesh.corner(f, 2);
    const Vec3 n = (b - a).cross(c - a).normalized();
    const Vec3 on = a + s * (b - a) + t * (c - a);
    Collider col = random_collider(rng, R * opt.collider_scale, on, rng.rotation());
    const double size = col.shape == ColliderShape::kSphere ? col.radius : col.half.maxCoeff();
    col.center = on + n * (size * rng.uniform(-1.5, 1.5));  // on, inside and near the surface
    engine.query(col);
  }
}

// ---- dynamic mode (ODE) --------------------------------------------------------------------

struct Scene {
  QueryEngine* engine = nullptr;
  Vec3 spin_center;
  std::array<Vec3, 8> root_corners;  // relative to spin_center
  dWorldID world = nullptr;
  dJointGroupID contacts = nullptr;
  dGeomID model = nullptr;
  uint64_t joints = 0;
  double R = 1;  // the model's bounding radius: the scene's unit of length
};

constexpr int kMaxContactsPerPair = 4;

Scene* scene_of(dGeomID g) {
  Scene* s;
  std::memcpy(&s, dGeomGetClassData(g), sizeof s);
  return s;
}

Eigen::Matrix3d rotation_of(dGeomID g) {
  const dReal* r = dGeomGetRotation(g);  // 3x4, row-major
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r[4 * i + j];
  return m;
}

Vec3 position_of(dGeomID g) {
  const dReal* p = dGeomGetPosition(g);
  return Vec3(p[0], p[1], p[2]);
}

void model_aabb(dGeomID g, dReal aabb[6]) {
  const Scene* s = scene_of(g);
  const Eigen::Matrix3d R = rotation_of(g);
  Aabb box;
  for (const Vec3& c : s->root_corners) box.extend(Vec3(R * c + position_of(g)));
  for (int i = 0; i < 3; ++i) {
    aabb[2 * i] = box.lo[i];
    aabb[2 * i + 1] = box.hi[i];
  }
}

// o1: the model, o2: a sphere or a box. Contacts from the touching faces, deepest first.
int model_collider(dGeomID o1, dGeomID o2, int flags, dContactGeom* out, int skip) {
  Scene* s = scene_of(o1);
  const Eigen::Matrix3d Rm = rotation_of(o1);
  const Vec3 pm = position_of(o1);
  // The collider in the model's frame (mesh coordinates): x = Rm^T (world - pm) + spin_center.
  Collider c;
  c.center = Rm.transpose() * (position_of(o2) - pm) + s->spin_center;
  if (dGeomGetClass(o2) == dSphereClass) {
    c.shape = ColliderShape::kSphere;
    c.radius = dGeomSphereGetRadius(o2);
  } else {
    c.shape = ColliderShape::kBox;
    dVector3 len;
    dGeomBoxGetLengths(o2, len);
    const Eigen::Matrix3d Rc = Rm.transpose() * rotation_of(o2);
    for (int k = 0; k < 3; ++k) {
      c.half[k] = 0.5 * len[k];
      c.axes[k] = Rc.col(k);
    }
  }
  const std::vector<int32_t>& faces = s->engine->query(c);
  const Mesh& mesh = s->engine->mesh();
  struct Candidate {
    double depth;
    int32_t face;
    Vec3 pos, normal;  // model frame; normal points out of the model
  };
  std::vector<Candidate> cands;
  for (int32_t f : faces) {
    const Vec3 a = mesh.corner(f, 0), b = mesh.corner(f, 1), cc = mesh.corner(f, 2);
    const Vec3 fn = (b - a).cross(cc - a).normalized();
    Candidate k{0, f, Vec3::Zero(), fn};
    if (c.shape == ColliderShape::kSphere) {
      k.pos = closest_point_on_triangle(c.center, a, b, cc);
      const Vec3 v = c.center - k.pos;
      const double d = v.norm();
      if (d > 1e-9 * c.radius) k.normal = v / d;
      k.depth = c.radius - d;
    } else {
      double deepest = -1e300;
      for (int i = 0; i < 8; ++i) {
        Vec3 corner = c.center;
        for (int j = 0; j < 3; ++j) corner += ((i >> j) & 1 ? 1.0 : -1.0) * c.half[j] * c.axes[j];
        const double d = fn.dot(a - corner);
        if (d > deepest) deepest = d, k.pos = corner;
      }
      k.depth = std::clamp(deepest, 0.0, 2 * c.half.maxCoeff());
    }
    cands.push_back(k);
  }
  std::sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) {
    return x.depth != y.depth ? x.depth > y.depth : x.face < y.face;
  });
  const int n =
      std::min<int>({static_cast<int>(cands.size()), flags & 0xffff, kMaxContactsPerPair});
  for (int i = 0; i < n; ++i) {
    dContactGeom* g = reinterpret_cast<dContactGeom*>(reinterpret_cast<char*>(out) + i * skip);
    const Vec3 pos = Rm * (cands[i].pos - s->spin_center) + pm;
    const Vec3 normal = -(Rm * cands[i].normal);  // into body 1, the model
    for (int j = 0; j < 3; ++j) g->pos[j] = pos[j], g->normal[j] = normal[j];
    g->pos[3] = g->normal[3] = 0;
    g->depth = cands[i].depth;
    g->g1 = o1;
    g->g2 = o2;
    g->side1 = g->side2 = -1;
  }
  return n;
}

dColliderFn* model_collider_for(int num) {
  return num == dSphereClass || num == dBoxClass ? &model_collider : nullptr;
}

int model_class() {
  static const int cls = [] {
    dInitODE2(0);
    dGeomClass c;
    c.bytes = sizeof(Scene*);
    c.collider = &model_collider_for;
    c.aabb = &model_aabb;
    c.aabb_test = nullptr;
    c.dtor = nullptr;
    return dCreateGeomClass(&c);
  }();
  return cls;
}

void near_callback(void* data, dGeomID o1, dGeomID o2) {
  Scene* s = static_cast<Scene*>(data);
  if (o2 == s->model) std::swap(o1, o2);
  dContactGeom geoms[kMaxContactsPerPair];
  const int n = dCollide(o1, o2, kMaxContactsPerPair, geoms, sizeof(dContactGeom));
  for (int i = 0; i < n; ++i) {
    dContact contact;
    std::memset(&contact, 0, sizeof contact);
    contact.surface.mode = dContactBounce | dContactSoftCFM | dContactApprox1;
    contact.surface.mu = 0.5;
    contact.surface.bounce = 0.3;
    // Scale-free: a bounce threshold in units of R per second (velocities scale with R,
    // gravity being 2 R/s^2); CFM, like ODE's ERP, is unitless once masses do not grow with R.
    contact.surface.bounce_vel = 0.05 * s->R;
    contact.surface.soft_cfm = 1e-4;
    contact.geom = geoms[i];
    const dJointID j = dJointCreateContact(s->world, s->contacts, &contact);
    dJointAttach(j, dGeomGetBody(o1), dGeomGetBody(o2));
    ++s->joints;
  }
}

// ODE reports through three global handlers: messages (warnings it goes on after), and errors
// and debug failures (after which it cannot go on). The last message is kept, so that the one
// line a failure ends with can say what led to it.
struct PhysicsFailure {
  static inline const ExperimentOptions* options = nullptr;
  static inline std::string last_message;
  static std::string format(int num, const char* msg, va_list ap) {
    char text[512];
    std::vsnprintf(text, sizeof text, msg, ap);
    std::string s = "ODE " + std::to_string(num) + ": " + text;
    for (char& c : s)
      if (c == '\n' || c == '\r') c = ' ';
    return s;
  }
  static void message(int num, const char* msg, va_list ap) { last_message = format(num, msg, ap); }
  [[noreturn]] static void fatal(int num, const char* msg, va_list ap) {
    std::string line = format(num, msg, ap);
    if (!last_message.empty()) line += " (after " + last_message + ")";
    if (options != nullptr && options->on_physics_failure) options->on_physics_failure(line);
    std::fprintf(stderr, "%s\n", line.c_str());
    std::abort();
  }
  explicit PhysicsFailure(const ExperimentOptions& opt) {
    options = &opt;
    last_message.clear();
    dSetMessageHandler(&message);
    dSetErrorHandler(&fatal);
    dSetDebugHandler(&fatal);
  }
  ~PhysicsFailure() {
    dSetMessageHandler(nullptr);
    dSetErrorHandler(nullptr);
    dSetDebugHandler(nullptr);
    options = nullptr;
  }
};

void run_dynamic(QueryEngine& engine, const Tree& first, const ExperimentOptions& opt,
                 ExperimentReport* report) {
  const int cls = model_class();
  const PhysicsFailure failure_handlers(opt);
  // ODE's quick step reorders constraints with its own global generator: reseed it per run.
  dRandSetSeed(static_cast<unsigned long>(opt.seed));
  Scene scene;
  scene.engine = &engine;
  const Obb& root = first.nodes[0].box;
  scene.spin_center = root.center;
  const std::array<Vec3, 8> corners = vobb::corners(root);
  double R = 0, top = -1e300, bottom = 1e300;
  for (int i = 0; i < 8; ++i) {
    scene.root_corners[i] = corners[i] - root.center;
    R = std::max(R, scene.root_corners[i].norm());
    top = std::max(top, corners[i].z());
    bottom = std::min(bottom, corners[i].z());
  }
  scene.R = R;
  scene.world = dWorldCreate();
  dWorldSetGravity(scene.world, 0, 0, -2.0 * R);  // a drop of 4R takes 2 s
  dWorldSetQuickStepNumIterations(scene.world, 20);
  dSpaceID space = dSimpleSpaceCreate(nullptr);
  scene.contacts = dJointGroupCreate(0);
  scene.model = dCreateGeom(cls);
  Scene* ptr = &scene;
  std::memcpy(dGeomGetClassData(scene.model), &ptr, sizeof ptr);
  dGeomSetPosition(scene.model, root.center.x(), root.center.y(), root.center.z());

  Random rng(opt.seed);
  struct Body {
    dBodyID body;
    dGeomID geom;
  };
  std::vector<Body> bodies;
  auto drop = [&](dBodyID body) {
    const double rho = R * std::sqrt(rng.uniform()), phi = 2 * M_PI * rng.uniform();
    const double z = top + 0.2 * R + 4 * R * rng.uniform();
    dBodySetPosition(body, root.center.x() + rho * std::cos(phi),
                     root.center.y() + rho * std::sin(phi), z);
    const Eigen::Quaterniond q(rng.rotation());
    const dQuaternion dq = {q.w(), q.x(), q.y(), q.z()};
    dBodySetQuaternion(body, dq);
    dBodySetLinearVel(body, 0, 0, 0);
    dBodySetAngularVel(body, 0, 0, 0);
  };
  for (int i = 0; i < opt.colliders; ++i) {
    Body b;
    b.body = dBodyCreate(scene.world);
    const Collider c =
        random_collider(rng, R * opt.collider_scale, Vec3::Zero(), Eigen::Matrix3d::Identity());
    // Density 1 / R^3: a collider's mass depends on its size relative to R, not on the
    // model's units, so forces scale with R like every length and the contacts' CFM keeps
    // its meaning (the scene is the same at any scale; exactly so for powers of two).
    const double density = 1.0 / (R * R * R);
    dMass mass;
    if (c.shape == ColliderShape::kSphere) {
      b.geom = dCreateSphere(space, c.radius);
      dMassSetSphere(&mass, density, c.radius);
    } else {
      b.geom = dCreateBox(space, 2 * c.half[0], 2 * c.half[1], 2 * c.half[2]);
      dMassSetBox(&mass, density, 2 * c.half[0], 2 * c.half[1], 2 * c.half[2]);
    }
    dBodySetMass(b.body, &mass);
    dGeomSetBody(b.geom, b.body);
    drop(b.body);
    bodies.push_back(b);
  }

  const double omega = 0.5 * M_PI;  // spin, rad/s: a quarter turn per second
  const long steps = std::lround(opt.seconds / opt.step);
  for (long k = 0; k < steps; ++k) {
    dMatrix3 R3;
    dRFromAxisAndAngle(R3, 0, 0, 1, omega * k * opt.step);
    dGeomSetRotation(scene.model, R3);
    dSpaceCollide2(scene.model, reinterpret_cast<dGeomID>(space), &scene, &near_callback);
    dWorldQuickStep(scene.world, opt.step);
    dJointGroupEmpty(scene.contacts);
    for (Body& b : bodies) {
      const dReal* p = dBodyGetPosition(b.body);
      const double dx = p[0] - root.center.x(), dy = p[1] - root.center.y();
      if (p[2] < bottom - R || dx * dx + dy * dy > 9 * R * R) drop(b.body);
    }
  }
  report->simulated_seconds = steps * opt.step;
  report->ode_contacts = scene.joints;
  dJointGroupDestroy(scene.contacts);
  dGeomDestroy(scene.model);
  dSpaceDestroy(space);  // destroys the colliders' geoms
  dWorldDestroy(scene.world);
}

}  // namespace

double reduction_pct(double first, double other) {
  return first > 0 ? 100.0 * (1.0 - other / first) : 0.0;
}

Status run_collision_experiment(const Mesh& mesh, const std::vector<NamedTree>& trees,
                                const ExperimentOptions& options, ExperimentReport* report) {
  if (trees.empty()) return Status::error("collide: no tree given");
  if (options.colliders < 1) return Status::error("collide: need at least one collider");
  if (!(options.collider_scale >= 0.01 && options.collider_scale <= 10))  // NaN fails too
    return Status::error("collide: the collider scale must be within [0.01, 10]");
  if (options.dynamic) {
    // Every collider is an ODE body of about 1.1 kB (measured: 123 MB for 10^5), all alive
    // at once, and ODE does not survive a failed allocation: 10^7 took 10.5 GB before the
    // first step. 10^6 keeps the scene near 1 GB.
    if (options.colliders > kMaxDynamicColliders)
      return Status::error(
          "collide: at most " + std::to_string(kMaxDynamicColliders) +
          " colliders in the dynamic scene (each is a physics body held in memory); "
          "use --static for more poses");
    // At most 10^9 steps; NaN fails every comparison.
    if (!(options.step > 0 && options.step <= 1) ||
        !(options.seconds >= 0 && options.seconds <= 1e9 * options.step))
      return Status::error(
          "collide: the time step must be in (0, 1] s and the simulated time in [0, 1e9 steps]");
  }
  for (const NamedTree& t : trees) {
    Status s = validate_tree(*t.tree, t.name);
    if (!s) return s;
    if (t.tree->mesh_triangles != mesh.faces.size())
      return Status::error(t.name + ": tree indexes " + std::to_string(t.tree->mesh_triangles) +
                           " triangles but the mesh has " + std::to_string(mesh.faces.size()));
    const ContainmentReport c = check_conservative(mesh, *t.tree, 1);
    if (!c.ok())
      return Status::error(t.name + ": not conservative: " + std::to_string(c.violations) +
                           " (node, face) pairs with a vertex outside the node's box");
  }
  *report = ExperimentReport();
  report->dynamic = options.dynamic;
  for (const NamedTree& t : trees) {
    TreeResult r;
    r.name = t.name;
    r.method = t.tree->method;
    r.depth = t.tree->depth;
    r.arity = t.tree->arity;
    r.nodes = t.tree->nodes.size();
    report->trees.push_back(r);
  }
  const uint64_t fallbacks0 = exact_fallbacks();
  QueryEngine engine(mesh, trees, options, report);
  if (options.dynamic)
    run_dynamic(engine, *trees[0].tree, options, report);
  else
    run_static(engine, *trees[0].tree, options);
  report->exact_fallbacks = exact_fallbacks() - fallbacks0;
  // Colliders start 0.2 R to 4.2 R above the model, a fall of at least 0.45 s: a shorter run
  // asks nothing, and "every answer agrees" would say nothing.
  if (report->queries == 0) {
    char why[200];
    std::snprintf(why, sizeof why,
                  "collide: no collider reached the model in %g simulated seconds (--seconds %g, "
                  "in whole steps of %g s; the first arrive after about 0.45 s); simulate longer",
                  report->simulated_seconds, options.seconds, options.step);
    return Status::error(why);
  }
  return Status::ok();
}

}  // namespace vobb::collision

// Internal data structures of libcram_native.
#pragma once
#include "cram_native.h"

#include <btBulletDynamicsCommon.h>
#include <cmath>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>
#if defined(__x86_64__) || defined(__i386__)
#include <xmmintrin.h>
#else
#include <cfenv>
#endif

namespace cn {

// ---- errors --------------------------------------------------------------------------------
struct Error : std::exception {
  int code;
  std::string msg;
  Error(int c, std::string m) : code(c), msg(std::move(m)) {}
  const char *what() const noexcept override { return msg.c_str(); }
};
[[noreturn]] void fail(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int set_error(int code, const std::string &msg);
void clear_error();
int guard_exception();  // call inside catch(...): converts the active exception to a status

// Every entry point runs under one process-wide lock: Lisp may call in from several threads at
// once (plan threads of one projection, the garbage collector's finalizer destroying a world),
// and worlds share collision shapes, meshes and the registries.
// The lock is recursive per thread (a depth counter in thread-local storage); taking it costs
// one atomic exchange and giving it back one plain store. A waiter spins briefly, then yields,
// then sleeps in short steps (the holder may be rendering for milliseconds).
extern std::atomic<int> g_api_lock;
extern thread_local int t_api_depth;
void api_lock_wait();
struct ApiLock {
  ApiLock() {
    if (t_api_depth++ == 0 && g_api_lock.exchange(1, std::memory_order_acquire)) api_lock_wait();
  }
  ~ApiLock() {
    if (--t_api_depth == 0) g_api_lock.store(0, std::memory_order_release);
  }
  ApiLock(const ApiLock &) = delete;
  ApiLock &operator=(const ApiLock &) = delete;
};

// The caller's floating point environment (SBCL traps on invalid, overflow and division by
// zero) is replaced by "all exceptions masked" for the duration of a call and restored, flags
// included, on return: Bullet, assimp and llvmpipe compute with infinities and NaNs
// internally, and their worker threads inherit the masked environment.
struct FpMasked {
#if defined(__x86_64__) || defined(__i386__)
  unsigned csr;
  FpMasked() : csr(_mm_getcsr()) { _mm_setcsr((csr | 0x1F80u) & ~0x3Fu); }
  ~FpMasked() { _mm_setcsr(csr); }
#else
  std::fenv_t env;
  FpMasked() { std::feholdexcept(&env); }
  ~FpMasked() { std::fesetenv(&env); }
#endif
  FpMasked(const FpMasked &) = delete;
  FpMasked &operator=(const FpMasked &) = delete;
};

// The lock and the exception barrier, without touching the floating point environment.
template <class F> inline int guard_unmasked(F &&f) {
  ApiLock lock;
  try {
    return f();
  } catch (...) {
    return guard_exception();
  }
}

template <class F> inline int guard(F &&f) {
  FpMasked fp;
  return guard_unmasked(f);
}

// True when the calling thread traps at most invalid, overflow and division by zero (SBCL's
// default; underflow, denormal and inexact masked) and each of the N values at P is zero or of
// magnitude in about [1e-100, 1e100] (binary exponent within +-330). Normalising and copying
// such a pose cannot raise any of those three, so an entry point that does nothing else may
// skip FpMasked, whose two writes of the control register cost more than the teleport itself.
bool fp_tame(const double *p, int n);

// ---- argument checks -----------------------------------------------------------------------
void check_ptr(const void *p, const char *what);
// an output buffer of CAP elements at P: CAP >= 0, and P not null when CAP > 0
void check_output(int cap, const void *p, const char *what);
double check_finite(double v, const char *what);
double check_positive(double v, const char *what);     // finite and > 0
double check_nonneg(double v, const char *what);       // finite and >= 0
btTransform read_pose(const double *p7, const char *what = "pose");

// The pose x y z qx qy qz qw at P (finite) into T, the quaternion normalised on the fly
// (s = 2 / |q|^2); false, T untouched, when |q| < 1e-9.
inline bool pose_into(const double *p, btTransform &t) {
  double x = p[3], y = p[4], z = p[5], w = p[6];
  double n2 = x * x + y * y + z * z + w * w;
  if (!(n2 >= 1e-18)) return false;
  double s = (n2 == 1.0) ? 2.0 : 2.0 / n2;
  double xs = x * s, ys = y * s, zs = z * s;
  double wx = w * xs, wy = w * ys, wz = w * zs;
  double xx = x * xs, xy = x * ys, xz = x * zs;
  double yy = y * ys, yz = y * zs, zz = z * zs;
  t.getBasis().setValue(1.0 - (yy + zz), xy - wz, xz + wy,
                        xy + wz, 1.0 - (xx + zz), yz - wx,
                        xz - wy, yz + wx, 1.0 - (xx + yy));
  t.getOrigin().setValue(p[0], p[1], p[2]);
  return true;
}
void write_pose(const btTransform &t, double *out7);
std::string check_str(const char *s, const char *what);

// ---- render geometry (shared, immutable) ------------------------------------------------------
struct RenderMesh {
  uint64_t id;                  // unique, never reused
  std::vector<float> pos;       // 9 per triangle
  std::vector<float> nrm;       // 9 per triangle
  RenderMesh();
  ~RenderMesh();                // its display list goes with it (forget_render_mesh)
  // the bounding box of its vertices, computed at the first call (once, from any thread)
  void bounds(btVector3 &lo, btVector3 &hi) const;

 private:
  mutable std::once_flag bounds_once_;
  mutable btVector3 lo_{0, 0, 0}, hi_{0, 0, 0};
};
void forget_render_mesh(uint64_t id);  // cn_render.cpp
using RenderMeshP = std::shared_ptr<const RenderMesh>;

struct RenderItem {
  RenderMeshP mesh;
  btTransform local;            // relative to the body / link frame
  btVector3 scale{1, 1, 1};
  float rgba[4] = {0.5f, 0.5f, 0.5f, 1.0f};
  bool has_color = false;       // colour from the model (URDF material)
};

// A pinhole camera (cn_render.cpp): its pose world <- camera in its convention
// (CN_CAMERA_OPTICAL: z forward, y down; CN_CAMERA_FORWARD: x forward, z up), vertical field of
// view in degrees, near and far planes (m), image size (pixels).
struct Camera {
  btTransform pose;
  int convention;
  double fov, near_m, far_m;
  int w, h;
};
// The camera of the arguments, checked (CN_E_ARG naming what is wrong).
Camera read_camera(const double *cam7, int convention, double fov, int w, int h, double n, double f);
btTransform gl_camera(const Camera &cam);  // world <- camera in OpenGL's frame (-z forward, y up)
// Half the width and half the height (m) of the camera's near plane: its frustum (glFrustum).
void frustum_half_extents(const Camera &cam, double &right, double &top);
// The camera pose at EYE looking at TARGET with UP roughly up, in CONVENTION.
btTransform look_at_tf(const btVector3 &eye, const btVector3 &target, btVector3 up, int convention);

// unit primitives for drawing
RenderMeshP unit_box();         // [-0.5, 0.5]^3
RenderMeshP unit_sphere();      // radius 1
RenderMeshP unit_cylinder();    // radius 1, z in [-0.5, 0.5]
RenderMeshP unit_cone();        // radius 1 at z=-0.5, apex at z=0.5
RenderMeshP plane_quad();       // 200 m x 200 m in the xy plane

// ---- collision shapes (shared between worlds, immutable) ----------------------------------------
struct Shape {
  btCollisionShape *shape = nullptr;
  std::vector<btCollisionShape *> children;   // owned sub-shapes
  std::vector<std::shared_ptr<Shape>> refs;   // shared sub-shapes kept alive
  btTriangleMesh *trimesh = nullptr;          // owned for triangle-mesh shapes
  std::vector<RenderItem> draw;               // render geometry in the shape frame
  int kind = 0;
  double dims[4] = {0, 0, 0, 0};
  ~Shape();
};
using ShapeP = std::shared_ptr<Shape>;

ShapeP make_plane(const btVector3 &n, double c);
ShapeP make_box(double sx, double sy, double sz);
ShapeP make_sphere(double r);
ShapeP make_cylinder(double r, double h);
ShapeP make_cone(double r, double h);
ShapeP make_hull(const double *pts, int n);
// How a mesh file becomes a collision shape: the exact triangle mesh (static bodies only), one
// convex hull per sub-mesh (children of a compound), or one convex hull over every vertex.
enum class MeshMode { Exact, Hulls, OneHull };
ShapeP load_mesh(const std::string &path, const btVector3 &scale, MeshMode mode);  // cached
RenderMeshP load_render_mesh(const std::string &path, const btVector3 &scale);   // cached
double shape_margin();
std::string resolve_path(const std::string &uri, const std::string &base_dir);

// ---- URDF model (shared, immutable) ---------------------------------------------------------
struct JointM {
  std::string name;
  int type = CN_JOINT_FIXED;
  int parent = -1, child = -1, mimic = -1;
  btTransform origin;
  btVector3 axis{1, 0, 0};
  double lower = 0, upper = 0, velocity = 0, effort = 0, mult = 1, offset = 0;
};
struct LinkM {
  std::string name;
  int parent_joint = -1;
  ShapeP collision;               // null: no rigid body
  std::vector<RenderItem> visual; // visual geometry (or collision geometry when absent)
};
struct Model {
  std::string name;
  std::vector<LinkM> links;
  std::vector<JointM> joints;
  std::vector<int> order;         // joints in topological order
  int root = 0;
  std::unordered_map<std::string, int> link_index, joint_index;
  // What the sweep checks need of each link (cn_sweep.cpp), made on first use and shared by
  // every world using the model; guarded by cache_mu.
  mutable std::mutex cache_mu;
  mutable std::shared_ptr<const void> sweep_links;
};
using ModelP = std::shared_ptr<const Model>;
ModelP parse_urdf(const std::string &xml, MeshMode meshes);

// ---- objects and worlds --------------------------------------------------------------------
struct World;
struct Object {
  int id = -1;
  int kind = CN_BODY;
  int group = 1, mask = -1;
  // body
  btRigidBody *rb = nullptr;
  ShapeP shape;
  double mass = 0;
  float rgba[4] = {0.5f, 0.5f, 0.5f, 1.0f};
  bool attached_kinematic = false;   // made kinematic by a rigid attachment
  // articulated object
  ModelP model;
  btTransform base = btTransform::getIdentity();
  std::vector<double> q;
  std::vector<btTransform> link_pose;
  std::vector<btRigidBody *> link_rb;           // null for links without collision
  std::vector<std::array<float, 4>> link_rgba;  // override colour (a < 0: model colours)
  bool self_collision = false;
  // the rotation of each revolute joint at the value it was last computed for (the value's
  // bits in joint_rot_bits), kept by robot_fk so that links are placed again without it
  std::vector<btMatrix3x3> joint_rot;
  std::vector<uint64_t> joint_rot_bits;
  // the sweep checks' view of its links (cn_sweep.cpp), made for its link shapes: kept here
  // once checked against them (null: not yet)
  std::shared_ptr<const void> sweep_links;
};

struct Attachment {
  int obj, parent, link;
  bool loose;
  btTransform rel;   // parent frame -> obj
};

class Dispatcher;
struct World {
  btDefaultCollisionConfiguration *config = nullptr;
  Dispatcher *dispatcher = nullptr;
  btBroadphaseInterface *broadphase = nullptr;
  btSequentialImpulseConstraintSolver *solver = nullptr;
  btDiscreteDynamicsWorld *dw = nullptr;
  std::vector<Object *> objects;          // index = handle; null = removed
  std::vector<Attachment> attachments;
  std::set<std::array<int, 4>> ignored;   // (objA, linkA, objB, linkB), A <= B
  // Bodies teleported since the last query (flag: user index 3 == 1). Their broadphase
  // bounding boxes are brought up to date once, by sync_aabbs(), before the next query that
  // reads the broadphase (contacts, rays, physics) or before bodies are deleted.
  std::vector<btCollisionObject *> stale_aabbs;
  World(const btVector3 &gravity);
  ~World();
  Object &obj(int h, const char *what = "object");
  Object &body(int h);
  Object &robot(int h);
  bool pair_ignored(int oa, int la, int ob, int lb) const;
};

World &world(int h);
int world_register(World *w);
void world_unregister(int h);

// operations used across files
btRigidBody *new_body(World &w, Object &o, const ShapeP &s, double mass, const btTransform &t);
void add_rb(World &w, btRigidBody *rb, int group, int mask);
void teleport_rb(World &w, btRigidBody *rb, const btTransform &t);  // AABB update deferred
bool teleport_rb_tame(World &w, btRigidBody *rb, const double *pose7);  // false: zero quaternion
void sync_aabbs(World &w);  // broadphase AABBs of the bodies teleported since the last sync
// The same but for the bodies of the objects KEEP_STALE (called with an object handle) is true
// for: queries that leave those objects out keep them on the list for the next sync.
void sync_aabbs_except(World &w, const std::function<bool(int)> &keep_stale);
void forget_stale_aabbs(World &w);  // after updateAabbs(), which has done every body
void set_object_pose(World &w, Object &o, const btTransform &t);
btTransform object_pose(const Object &o);
btTransform frame_pose(const Object &o, int link);   // link pose or body pose
// The value of joint J of model M for the joint values Q (a mimic joint follows its joint).
inline double joint_value(const Model &m, const std::vector<double> &q, int j) {
  const JointM &jm = m.joints[j];
  return jm.mimic >= 0 ? jm.mult * q[jm.mimic] + jm.offset : q[j];
}

// The pose of joint JM's child link, its parent link at PARENT and the joint at value V.
inline btTransform child_pose(const JointM &jm, const btTransform &parent, double v) {
  btTransform t = parent * jm.origin;
  switch (jm.type) {
    case CN_JOINT_REVOLUTE:
    case CN_JOINT_CONTINUOUS:
      t.setBasis(t.getBasis() * btMatrix3x3(btQuaternion(jm.axis, v)));
      break;
    case CN_JOINT_PRISMATIC:
      t.setOrigin(t * (jm.axis * v));
      break;
    default:
      break;
  }
  return t;
}

void robot_fk(World &w, Object &o);
// After O's joint values changed from OLD_Q (its base kept): ROBOT_FK of the links a changed
// joint moves.
void robot_fk_changed(World &w, Object &o, const std::vector<double> &old_q);
void compute_link_poses(const Object &o, std::vector<btTransform> &out);
// Link poses of model M for the base pose BASE and joint values Q (mimic joints follow); with
// NEEDED, only the links marked there (every ancestor of a marked link must be marked too).
void compute_link_poses(const Model &m, const btTransform &base, const std::vector<double> &q,
                        std::vector<btTransform> &out, const std::vector<char> *needed = nullptr);
// The same for the child links of JOINTS only (in model order; the other links' poses in OUT are
// left as they are, and are read where a child's parent is not among them).
void compute_link_poses_of(const Model &m, const btTransform &base, const std::vector<double> &q,
                           std::vector<btTransform> &out, const std::vector<int> &joints);
double model_joint_value(const Model &m, const std::vector<double> &q, int j);  // mimic applied
void set_query_all(World &w, bool on);
void move_attached(World &w, int parent, int depth = 0);
void robot_new_bodies(World &w, Object &o);
void remove_object_bodies(World &w, Object &o);
void for_each_rb(const Object &o, const std::function<void(btRigidBody *, int)> &f);
// a plain body of shape s at pose (mass 0: static) in world wh -> its handle (cn_world.cpp)
int add_body(int wh, const double *pose, ShapeP s, double mass, const char *what);
// Union of the AABBs of the bodies of o (or of its link `link`, -1 = all); false if it has none.
bool union_aabb(const Object &o, int link, btVector3 &lo, btVector3 &hi);
void check_link_arg(const Object &o, int oh, int link);  // -1 or a link of an articulated one

inline void decode_rb(const btCollisionObject *co, int &obj, int &link) {
  obj = co->getUserIndex();
  link = co->getUserIndex2();
}

std::string fmt(const char *f, ...) __attribute__((format(printf, 1, 2)));
// a number for messages: NaN, inf, -inf or %g
std::string num(double v);

}  // namespace cn

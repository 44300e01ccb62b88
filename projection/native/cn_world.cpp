// Worlds, objects, rigid bodies, poses and world copies.
#include "cn_internal.hpp"

#include <cstring>
#include <optional>

namespace cn {

class Dispatcher : public btCollisionDispatcher {
 public:
  World *w;
  bool query_all = false;   // during contact queries: also static/sleeping pairs
  Dispatcher(btCollisionConfiguration *c, World *wd) : btCollisionDispatcher(c), w(wd) {}
  bool needsCollision(const btCollisionObject *a, const btCollisionObject *b) override {
    if (!query_all && !btCollisionDispatcher::needsCollision(a, b)) return false;
    int oa, la, ob, lb;
    decode_rb(a, oa, la);
    decode_rb(b, ob, lb);
    return !w->pair_ignored(oa, la, ob, lb);
  }
};

void set_query_all(World &w, bool on) { w.dispatcher->query_all = on; }

World::World(const btVector3 &g) {
  // Small pools: Bullet takes the manifolds and collision algorithms beyond them from the heap,
  // while a pool is allocated and written through whenever a world is made. Pools of 256 (a
  // third of a megabyte, mapped afresh each time) made a copy of the kitchen world cost
  // 1.06 ms in fresh memory, pools of 64 0.64 ms; in the household demo a copy takes 0.45 ms
  // with pools of 64, 0.57 ms with 256, and the runs are no slower.
  btDefaultCollisionConstructionInfo ci;
  ci.m_defaultMaxPersistentManifoldPoolSize = 64;
  ci.m_defaultMaxCollisionAlgorithmPoolSize = 64;
  config = new btDefaultCollisionConfiguration(ci);
  dispatcher = new Dispatcher(config, this);
  // The broadphase finds the overlapping pairs when the physics or a whole-world contact query
  // asks for them (btDbvtBroadphase::collide), not whenever a body is added or moved: most
  // worlds are copies for queries that never read the pairs (rays, contact tests, sweeps), and
  // a copy searched every added body's pairs as it went: copying the kitchen world with the PR2
  // took 445 microseconds that way and takes 220-270 now, destroying it 94 and 58-72.
  auto *dbvt = new btDbvtBroadphase();
  dbvt->m_deferedcollide = true;
  broadphase = dbvt;
  solver = new btSequentialImpulseConstraintSolver();
  dw = new btDiscreteDynamicsWorld(dispatcher, broadphase, solver, config);
  dw->setGravity(g);
}

World::~World() {
  // The bodies teleported since the last query are not brought up to date in the broadphase:
  // that would find their new pairs only for the removals below to search them out again.
  forget_stale_aabbs(*this);
  // Drop every overlapping pair at once, from the end of the pair array: removing the bodies
  // one by one below would otherwise search all pairs for each body's (quadratic in bodies).
  btOverlappingPairCache *pairs = broadphase->getOverlappingPairCache();
  btBroadphasePairArray &arr = pairs->getOverlappingPairArray();
  for (int i = arr.size() - 1; i >= 0; --i) {
    btBroadphaseProxy *a = arr[i].m_pProxy0, *b = arr[i].m_pProxy1;
    pairs->removeOverlappingPair(a, b, dispatcher);
  }
  for (Object *o : objects)
    if (o) {
      remove_object_bodies(*this, *o);
      delete o;
    }
  delete dw;
  delete solver;
  delete broadphase;
  delete dispatcher;
  delete config;
}

Object &World::obj(int h, const char *what) {
  if (h < 0 || h >= (int)objects.size() || !objects[h])
    fail(CN_E_HANDLE, "%s handle %d is not a live object of this world", what, h);
  return *objects[h];
}
Object &World::body(int h) {
  Object &o = obj(h, "body");
  if (o.kind != CN_BODY) fail(CN_E_HANDLE, "object %d is an articulated object, not a body", h);
  return o;
}
Object &World::robot(int h) {
  Object &o = obj(h, "articulated object");
  if (o.kind != CN_ARTICULATED)
    fail(CN_E_HANDLE, "object %d is a rigid body, not an articulated object", h);
  return o;
}

bool World::pair_ignored(int oa, int la, int ob, int lb) const {
  if (oa == ob) {
    const Object *o = (oa >= 0 && oa < (int)objects.size()) ? objects[oa] : nullptr;
    return !(o && o->kind == CN_ARTICULATED && o->self_collision);
  }
  if (ignored.empty()) return false;
  if (oa > ob) {
    std::swap(oa, ob);
    std::swap(la, lb);
  }
  return ignored.count({oa, la, ob, lb}) || ignored.count({oa, -1, ob, lb}) ||
         ignored.count({oa, la, ob, -1}) || ignored.count({oa, -1, ob, -1});
}

void for_each_rb(const Object &o, const std::function<void(btRigidBody *, int)> &f) {
  if (o.kind == CN_BODY) {
    if (o.rb) f(o.rb, -1);
  } else {
    for (size_t i = 0; i < o.link_rb.size(); ++i)
      if (o.link_rb[i]) f(o.link_rb[i], (int)i);
  }
}

void add_rb(World &w, btRigidBody *rb, int group, int mask) { w.dw->addRigidBody(rb, group, mask); }

btRigidBody *new_body(World &w, Object &o, const ShapeP &s, double mass, const btTransform &t) {
  btVector3 inertia(0, 0, 0);
  if (mass > 0) s->shape->calculateLocalInertia(mass, inertia);
  btRigidBody::btRigidBodyConstructionInfo ci(mass, nullptr, s->shape, inertia);
  ci.m_startWorldTransform = t;
  auto *rb = new btRigidBody(ci);
  rb->setUserIndex(o.id);
  rb->setUserIndex2(-1);
  return rb;
}

static inline void teleport_to(World &w, btRigidBody *rb, const btTransform &t) {
  rb->setWorldTransform(t);
  rb->setInterpolationWorldTransform(t);
  if (rb->isStaticOrKinematicObject()) {
    rb->setInterpolationLinearVelocity(btVector3(0, 0, 0));
    rb->setInterpolationAngularVelocity(btVector3(0, 0, 0));
  } else {
    rb->activate(true);
  }
  if (rb->getUserIndex3() != 1) {
    rb->setUserIndex3(1);
    w.stale_aabbs.push_back(rb);
  }
}

void teleport_rb(World &w, btRigidBody *rb, const btTransform &t) { teleport_to(w, rb, t); }

bool teleport_rb_tame(World &w, btRigidBody *rb, const double *pose) {
  btTransform t;
  if (!pose_into(pose, t)) return false;
  teleport_to(w, rb, t);
  return true;
}

void forget_stale_aabbs(World &w) {
  for (btCollisionObject *co : w.stale_aabbs) co->setUserIndex3(0);
  w.stale_aabbs.clear();
}

void sync_aabbs(World &w) {
  for (btCollisionObject *co : w.stale_aabbs)
    if (co->getBroadphaseHandle()) w.dw->updateSingleAabb(co);
  forget_stale_aabbs(w);
}

void sync_aabbs_except(World &w, const std::function<bool(int)> &keep_stale) {
  size_t kept = 0;
  for (btCollisionObject *co : w.stale_aabbs) {
    if (keep_stale(co->getUserIndex())) {
      w.stale_aabbs[kept++] = co;
      continue;
    }
    if (co->getBroadphaseHandle()) w.dw->updateSingleAabb(co);
    co->setUserIndex3(0);
  }
  w.stale_aabbs.resize(kept);
}

btTransform object_pose(const Object &o) {
  return o.kind == CN_BODY ? o.rb->getWorldTransform() : o.base;
}

btTransform frame_pose(const Object &o, int link) {
  if (o.kind == CN_BODY) return o.rb->getWorldTransform();
  if (link < 0) return o.base;
  return o.link_pose[link];
}

void set_object_pose(World &w, Object &o, const btTransform &t) {
  if (o.kind == CN_BODY) {
    teleport_rb(w, o.rb, t);
  } else if (!(o.base == t && o.link_pose.size() == o.model->links.size())) {
    // (a third of the base poses a robot is given are the one it has: searches put it back)
    o.base = t;
    robot_fk(w, o);
  }
  move_attached(w, o.id);
}

void remove_object_bodies(World &w, Object &o) {
  sync_aabbs(w);  // no deleted body may stay on the list
  for_each_rb(o, [&](btRigidBody *rb, int) {
    w.dw->removeRigidBody(rb);
    delete rb;
  });
  o.rb = nullptr;
  for (auto &r : o.link_rb) r = nullptr;
}

static int add_object(World &w, Object *o) {
  o->id = (int)w.objects.size();
  w.objects.push_back(o);
  return o->id;
}

int add_body(int wh, const double *pose, ShapeP s, double mass, const char *what) {
  World &w = world(wh);
  btTransform t = read_pose(pose);
  check_nonneg(mass, "mass");
  std::unique_ptr<Object> o(new Object);
  o->kind = CN_BODY;
  o->shape = s;
  o->mass = mass;
  if (mass == 0) {
    o->group = 2;
    o->mask = -1 ^ 2;
  }
  o->id = (int)w.objects.size();
  o->rb = new_body(w, *o, s, mass, t);
  o->rb->setFriction(0.8);
  o->rb->setRollingFriction(0.0);
  add_rb(w, o->rb, o->group, o->mask);
  (void)what;
  return add_object(w, o.release());
}

static btRigidBody *clone_rb(const btRigidBody *src) {
  btRigidBody::btRigidBodyConstructionInfo ci(src->getInvMass() > 0 ? 1.0 / src->getInvMass() : 0,
                                              nullptr,
                                              const_cast<btCollisionShape *>(src->getCollisionShape()),
                                              btVector3(0, 0, 0));
  ci.m_startWorldTransform = src->getWorldTransform();
  auto *rb = new btRigidBody(ci);
  rb->setMassProps(ci.m_mass, src->getLocalInertia());
  rb->setCollisionFlags(src->getCollisionFlags());
  rb->setInterpolationWorldTransform(src->getInterpolationWorldTransform());
  rb->setLinearVelocity(src->getLinearVelocity());
  rb->setAngularVelocity(src->getAngularVelocity());
  rb->setInterpolationLinearVelocity(src->getInterpolationLinearVelocity());
  rb->setInterpolationAngularVelocity(src->getInterpolationAngularVelocity());
  rb->setFriction(src->getFriction());
  rb->setRollingFriction(src->getRollingFriction());
  rb->setRestitution(src->getRestitution());
  rb->setDamping(src->getLinearDamping(), src->getAngularDamping());
  rb->setUserIndex(src->getUserIndex());
  rb->setUserIndex2(src->getUserIndex2());
  rb->setGravity(src->getGravity());
  rb->forceActivationState(src->getActivationState());
  rb->setDeactivationTime(src->getDeactivationTime());
  rb->applyCentralForce(src->getTotalForce());
  rb->applyTorque(src->getTotalTorque());
  return rb;
}

World *copy_world(World &src) {
  std::unique_ptr<World> w(new World(src.dw->getGravity()));
  w->objects.resize(src.objects.size(), nullptr);
  for (size_t i = 0; i < src.objects.size(); ++i)
    if (src.objects[i]) {
      Object *o = new Object(*src.objects[i]);
      o->rb = nullptr;
      for (auto &r : o->link_rb) r = nullptr;
      o->sweep_links = nullptr;
      w->objects[i] = o;
    }
  auto &arr = src.dw->getCollisionObjectArray();
  for (int i = 0; i < arr.size(); ++i) {
    auto *srb = btRigidBody::upcast(arr[i]);
    if (!srb) continue;
    Object *o = w->objects[srb->getUserIndex()];
    btRigidBody *rb = clone_rb(srb);
    if (o->kind == CN_BODY) o->rb = rb;
    else o->link_rb[srb->getUserIndex2()] = rb;
    auto *proxy = srb->getBroadphaseHandle();
    w->dw->addRigidBody(rb, proxy->m_collisionFilterGroup, proxy->m_collisionFilterMask);
    rb->setGravity(srb->getGravity());
  }
  w->attachments = src.attachments;
  w->ignored = src.ignored;
  return w.release();
}

static void check_count(int n, const char *what) {
  if (n < 0) fail(CN_E_ARG, "%s is %d, expected >= 0", what, n);
}

}  // namespace cn

using namespace cn;

extern "C" {

int cn_world_create(double gx, double gy, double gz) {
  return guard([&] {
    btVector3 g(check_finite(gx, "gravity x"), check_finite(gy, "gravity y"),
                check_finite(gz, "gravity z"));
    std::unique_ptr<World> w(new World(g));
    int h = world_register(w.get());
    w.release();
    return h;
  });
}

int cn_world_destroy(int wh) {
  return guard([&] {
    World *w = &world(wh);
    world_unregister(wh);
    delete w;
    return 0;
  });
}

int cn_world_copy(int wh) {
  return guard([&] {
    std::unique_ptr<World> w(copy_world(world(wh)));
    int h = world_register(w.get());
    w.release();
    return h;
  });
}

int cn_world_set_gravity(int wh, double gx, double gy, double gz) {
  return guard([&] {
    World &w = world(wh);
    btVector3 g(check_finite(gx, "gravity x"), check_finite(gy, "gravity y"),
                check_finite(gz, "gravity z"));
    w.dw->setGravity(g);
    for (Object *o : w.objects)
      if (o) for_each_rb(*o, [&](btRigidBody *rb, int) {
          if (!rb->isStaticOrKinematicObject()) { rb->setGravity(g); rb->activate(true); }
        });
    return 0;
  });
}

int cn_world_get_gravity(int wh, double *out) {
  return guard([&] {
    World &w = world(wh);
    check_ptr(out, "gravity output");
    btVector3 g = w.dw->getGravity();
    out[0] = g.x(); out[1] = g.y(); out[2] = g.z();
    return 0;
  });
}

}  // extern "C"

namespace {
// Kinematic bodies (robot and environment links, rigidly attached objects) stand still while
// the physics runs: put them to sleep so that Bullet neither saves their kinematic state nor
// recomputes their bounding boxes every step, and wake them when the steps are done. Dynamic
// bodies still collide with them (one active body of a pair is enough).
struct KinematicRest {
  btDiscreteDynamicsWorld *dw;
  std::vector<btCollisionObject *> slept;
  explicit KinematicRest(World &w) : dw(w.dw) {
    btCollisionObjectArray &all = dw->getCollisionObjectArray();
    // the bounding boxes of the bodies teleported since the last query, and of the dynamic
    // bodies (the last steps moved them), before the kinematic bodies stop being updated; the
    // others are what they were (updating every body moved each into the broadphase's dynamic
    // tree, to be searched for its pairs again)
    sync_aabbs(w);
    for (int i = 0; i < all.size(); ++i)
      if (!all[i]->isStaticOrKinematicObject()) dw->updateSingleAabb(all[i]);
    for (int i = 0; i < all.size(); ++i) {
      btCollisionObject *co = all[i];
      if (co->isKinematicObject() && co->getActivationState() == DISABLE_DEACTIVATION) {
        co->forceActivationState(ISLAND_SLEEPING);
        slept.push_back(co);
      }
    }
    dw->setForceUpdateAllAabbs(false);
  }
  ~KinematicRest() {
    for (btCollisionObject *co : slept) co->forceActivationState(DISABLE_DEACTIVATION);
    dw->setForceUpdateAllAabbs(true);
  }
};

// For the steps of one simulate call (after KinematicRest brought the boxes up to date): the
// pairs of everything added or moved since the last steps are searched at once (outside the
// physics the broadphase defers that search, see World::World), and during the steps the
// moving bodies' pairs are found as they move, as Bullet does by default, not by searching
// the broadphase's trees every step. A single step searches the trees once anyway, and needs
// none of this.
struct PairsFoundAsBodiesMove {
  btDbvtBroadphase *bp;
  explicit PairsFoundAsBodiesMove(World &w) : bp(static_cast<btDbvtBroadphase *>(w.broadphase)) {
    bp->calculateOverlappingPairs(w.dispatcher);
    bp->m_deferedcollide = false;
  }
  ~PairsFoundAsBodiesMove() { bp->m_deferedcollide = true; }
};
const double CN_REST_SPEED = 1e-2, CN_REST_SPIN = 1e-1, CN_REST_TIME = 0.1;

bool all_dynamic_bodies_resting(World &w) {
  btCollisionObjectArray &all = w.dw->getCollisionObjectArray();
  for (int i = 0; i < all.size(); ++i) {
    const btRigidBody *rb = btRigidBody::upcast(all[i]);
    if (!rb || rb->isStaticOrKinematicObject() || !rb->isActive()) continue;
    if (rb->getLinearVelocity().length() >= CN_REST_SPEED ||
        rb->getAngularVelocity().length() >= CN_REST_SPIN)
      return false;
  }
  return true;
}

bool any_dynamic_body_awake(World &w) {
  btCollisionObjectArray &all = w.dw->getCollisionObjectArray();
  for (int i = 0; i < all.size(); ++i) {
    const btCollisionObject *co = all[i];
    if (!co->isStaticOrKinematicObject() && co->isActive()) return true;
  }
  return false;
}
}  // namespace

extern "C" {

int cn_world_step(int wh, double dt) {
  return guard([&] {
    World &w = world(wh);
    check_positive(dt, "time step dt");
    KinematicRest rest(w);
    w.dw->stepSimulation(dt, 0, dt);
    return 0;
  });
}

int cn_world_simulate(int wh, double seconds, double dt) {
  return guard([&] {
    World &w = world(wh);
    check_nonneg(seconds, "simulated seconds");
    check_positive(dt, "time step dt");
    double steps = std::ceil(seconds / dt - 1e-9);
    if (steps > 1e8) fail(CN_E_ARG, "simulate %g s at dt %g needs %g steps, limit 1e8", seconds, dt, steps);
    int n = (int)steps;
    KinematicRest rest(w);
    std::optional<PairsFoundAsBodiesMove> pairs;
    if (n > 1 && any_dynamic_body_awake(w)) pairs.emplace(w);
    // Stop early once nothing moves: every dynamic body asleep (Bullet zeroes the velocities
    // of a sleeping island), or every awake one slower than CN_REST_SPEED m/s and
    // CN_REST_SPIN rad/s for CN_REST_TIME s of simulated time. A body at rest stays at rest,
    // so the world is then as after all n steps (up to the solver's sub-millimetre jitter).
    double quiet = 0.0;
    for (int i = 0; i < n && any_dynamic_body_awake(w); ++i) {
      w.dw->stepSimulation(dt, 0, dt);
      quiet = all_dynamic_bodies_resting(w) ? quiet + dt : 0.0;
      if (quiet >= CN_REST_TIME - 1e-12) break;
    }
    return n;
  });
}

int cn_world_num_objects(int wh) {
  return guard([&] {
    World &w = world(wh);
    int n = 0;
    for (Object *o : w.objects) n += o != nullptr;
    return n;
  });
}

int cn_world_num_bodies(int wh) {
  return guard([&] { return world(wh).dw->getNumCollisionObjects(); });
}

int cn_world_objects(int wh, int *out, int cap) {
  return guard([&] {
    World &w = world(wh);
    check_count(cap, "capacity");
    if (cap > 0) check_ptr(out, "object output");
    int n = 0;
    for (Object *o : w.objects)
      if (o) {
        if (n < cap) out[n] = o->id;
        ++n;
      }
    return n;
  });
}

int cn_object_kind(int wh, int oh) {
  return guard([&] { return world(wh).obj(oh).kind; });
}

int cn_object_remove(int wh, int oh) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    std::vector<Attachment> keep;
    for (auto &a : w.attachments)
      if (a.obj != oh && a.parent != oh) keep.push_back(a);
      else if (a.parent == oh && !a.loose) {
        Object *c = w.objects[a.obj];
        if (c && c->attached_kinematic && c->rb) {
          c->rb->setCollisionFlags(c->rb->getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
          btVector3 in(0, 0, 0);
          c->shape->shape->calculateLocalInertia(c->mass, in);
          c->rb->setMassProps(c->mass, in);
          c->rb->setGravity(w.dw->getGravity());
          c->rb->activate(true);
          c->attached_kinematic = false;
        }
      }
    w.attachments.swap(keep);
    for (auto it = w.ignored.begin(); it != w.ignored.end();)
      if ((*it)[0] == oh || (*it)[2] == oh) it = w.ignored.erase(it);
      else ++it;
    remove_object_bodies(w, o);
    w.objects[oh] = nullptr;
    delete &o;
    return 0;
  });
}

int cn_object_get_pose(int wh, int oh, double *out) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    check_ptr(out, "pose output");
    write_pose(object_pose(o), out);
    return 0;
  });
}

// A body carrying no rigid attachment, teleported to a tame pose, runs without FpMasked: the
// call only normalises the quaternion and copies transforms (bounding boxes are deferred).
static bool carries_attachments(const World &w, int oh) {
  for (const Attachment &a : w.attachments)
    if (a.parent == oh && !a.loose) return true;
  return false;
}

int cn_object_set_pose(int wh, int oh, const double *pose) {
  auto body = [&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    set_object_pose(w, o, read_pose(pose));
    return 0;
  };
  if (!fp_tame(pose, 7)) return guard(body);
  int r = guard_unmasked([&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    if (o.kind != CN_BODY || carries_attachments(w, oh)) return 1;  // needs the masked path
    return teleport_rb_tame(w, o.rb, pose) ? 0 : 1;  // a zero quaternion fails on that path
  });
  return r == 1 ? guard(body) : r;
}

int cn_object_get_poses(int wh, const int *objs, int n, double *out) {
  return guard([&] {
    World &w = world(wh);
    check_count(n, "object count");
    if (n == 0) return 0;
    check_ptr(objs, "object array");
    check_ptr(out, "pose output");
    for (int i = 0; i < n; ++i) write_pose(object_pose(w.obj(objs[i])), out + 7 * i);
    return 0;
  });
}

int cn_object_set_poses(int wh, const int *objs, int n, const double *poses) {
  return guard([&] {
    World &w = world(wh);
    check_count(n, "object count");
    if (n == 0) return 0;
    check_ptr(objs, "object array");
    check_ptr(poses, "pose array");
    for (int i = 0; i < n; ++i) {  // validate everything first: all or nothing
      w.obj(objs[i]);
      std::string what = fmt("pose %d", i);
      read_pose(poses + 7 * i, what.c_str());
    }
    for (int i = 0; i < n; ++i) set_object_pose(w, w.obj(objs[i]), read_pose(poses + 7 * i));
    return 0;
  });
}

int cn_object_set_color(int wh, int oh, int link, double r, double g, double b, double a) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    double c[4] = {r, g, b, a};
    for (int i = 0; i < 4; ++i)
      if (!std::isfinite(c[i]) || c[i] < 0 || c[i] > 1)
        fail(CN_E_ARG, "colour component %d is %s, expected a number in [0, 1]", i, num(c[i]).c_str());
    if (o.kind == CN_BODY) {
      if (link != -1) fail(CN_E_HANDLE, "link %d given for body %d, expected -1", link, oh);
      for (int i = 0; i < 4; ++i) o.rgba[i] = (float)c[i];
    } else {
      if (link < -1 || link >= (int)o.link_rgba.size())
        fail(CN_E_HANDLE, "link index %d out of range 0..%d in articulated object %d", link,
             (int)o.link_rgba.size() - 1, oh);
      for (size_t l = 0; l < o.link_rgba.size(); ++l)
        if (link == -1 || (int)l == link)
          for (int i = 0; i < 4; ++i) o.link_rgba[l][i] = (float)c[i];
    }
    return 0;
  });
}

// The colour a link of the articulated object O is drawn in: its own when one was set, else
// its first visual's colour, else grey.
static const float *link_color(const Object &o, int link) {
  if (o.link_rgba[link][3] >= 0) return o.link_rgba[link].data();
  static const float grey[4] = {0.5f, 0.5f, 0.5f, 1.0f};
  for (auto &it : o.model->links[link].visual)
    if (it.has_color) return it.rgba;
  return grey;
}

int cn_object_get_color(int wh, int oh, int link, double *out) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    check_ptr(out, "colour output");
    const float *c = o.rgba;
    if (o.kind == CN_ARTICULATED) {
      if (link < 0 || link >= (int)o.link_rgba.size())
        fail(CN_E_HANDLE, "link index %d out of range 0..%d in articulated object %d", link,
             (int)o.link_rgba.size() - 1, oh);
      c = link_color(o, link);
    }
    for (int i = 0; i < 4; ++i) out[i] = c[i];
    return 0;
  });
}

int cn_robot_link_colors(int wh, int r, double *out, int cap) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    check_output(cap, out, "colour output");
    int n = (int)o.link_rgba.size();
    for (int l = 0; l < n && l < cap; ++l) {
      const float *c = link_color(o, l);
      for (int i = 0; i < 4; ++i) out[4 * l + i] = c[i];
    }
    return n;
  });
}

int cn_object_set_collision_filter(int wh, int oh, int group, int mask) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    o.group = group;
    o.mask = mask;
    for_each_rb(o, [&](btRigidBody *rb, int) {
      w.dw->removeRigidBody(rb);
      w.dw->addRigidBody(rb, group, mask);
    });
    return 0;
  });
}

int cn_object_get_collision_filter(int wh, int oh, int *out) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    check_ptr(out, "filter output");
    out[0] = o.group;
    out[1] = o.mask;
    return 0;
  });
}

}  // extern "C"

void cn::check_link_arg(const Object &o, int oh, int link) {
  if (o.kind == CN_BODY && link != -1)
    fail(CN_E_HANDLE, "link %d given for body %d, expected -1", link, oh);
  if (o.kind == CN_ARTICULATED && (link < -1 || link >= (int)o.link_rb.size()))
    fail(CN_E_HANDLE, "link index %d out of range -1..%d in articulated object %d", link,
         (int)o.link_rb.size() - 1, oh);
}

bool cn::union_aabb(const Object &o, int link, btVector3 &lo, btVector3 &hi) {
  lo = btVector3(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
  hi = -lo;
  bool any = false;
  if (link >= 0 && o.kind == CN_ARTICULATED) {  // that link's body alone
    btRigidBody *rb = link < (int)o.link_rb.size() ? o.link_rb[link] : nullptr;
    if (rb) rb->getCollisionShape()->getAabb(rb->getWorldTransform(), lo, hi);
    return rb != nullptr;
  }
  for_each_rb(o, [&](btRigidBody *rb, int l) {
    if (link >= 0 && l != link) return;
    btVector3 a, b;
    rb->getCollisionShape()->getAabb(rb->getWorldTransform(), a, b);
    lo.setMin(a);
    hi.setMax(b);
    any = true;
  });
  return any;
}

extern "C" {

int cn_object_aabb(int wh, int oh, int link, double *out) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    check_ptr(out, "AABB output");
    check_link_arg(o, oh, link);
    btVector3 lo, hi;
    if (!union_aabb(o, link, lo, hi)) {
      btVector3 p = frame_pose(o, link).getOrigin();
      lo = hi = p;
    }
    out[0] = lo.x(); out[1] = lo.y(); out[2] = lo.z();
    out[3] = hi.x(); out[4] = hi.y(); out[5] = hi.z();
    return 0;
  });
}

int cn_object_is_active(int wh, int oh) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    int active = 0;
    for_each_rb(o, [&](btRigidBody *rb, int) {
      if (!rb->isStaticOrKinematicObject() && rb->isActive()) active = 1;
    });
    return active;
  });
}

}  // extern "C"

// The limit for the cram-native benchmark: the same operations written directly against
// Bullet (double precision), with no handles, validation or foreign calls.
// Prints "name seconds-per-operation" lines.
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;

// Fastest of 5 batches of N calls (after a warm-up): the time of one call, as the Lisp side
// measures its own (bench-lib's time-per-call :best t).
template <class F> static double per_call(F f, int n) {
  for (int i = 0; i < n / 10 + 1; ++i) f(i);
  std::vector<double> t;
  for (int b = 0; b < 5; ++b) {
    auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) f(i);
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / n);
  }
  return *std::min_element(t.begin(), t.end());
}

struct World {
  btDefaultCollisionConfiguration *config;
  btCollisionDispatcher *disp;
  btDbvtBroadphase *bp;
  btSequentialImpulseConstraintSolver *solver;
  btDiscreteDynamicsWorld *dw;
  World() {
    btDefaultCollisionConstructionInfo ci;
    ci.m_defaultMaxPersistentManifoldPoolSize = 256;
    ci.m_defaultMaxCollisionAlgorithmPoolSize = 256;
    config = new btDefaultCollisionConfiguration(ci);
    disp = new btCollisionDispatcher(config);
    bp = new btDbvtBroadphase();
    solver = new btSequentialImpulseConstraintSolver();
    dw = new btDiscreteDynamicsWorld(disp, bp, solver, config);
    dw->setGravity(btVector3(0, 0, -9.81));
  }
  ~World() {
    for (int i = dw->getNumCollisionObjects() - 1; i >= 0; --i) {
      auto *o = dw->getCollisionObjectArray()[i];
      dw->removeCollisionObject(o);
      delete o;
    }
    delete dw; delete solver; delete bp; delete disp; delete config;
  }
  btRigidBody *add(btCollisionShape *s, double mass, const btTransform &t, int group, int mask,
                   bool kinematic = false) {
    btVector3 in(0, 0, 0);
    if (mass > 0) s->calculateLocalInertia(mass, in);
    btRigidBody::btRigidBodyConstructionInfo ci(mass, nullptr, s, in);
    ci.m_startWorldTransform = t;
    auto *rb = new btRigidBody(ci);
    if (kinematic) {
      rb->setCollisionFlags(rb->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      rb->setActivationState(DISABLE_DEACTIVATION);
    }
    dw->addRigidBody(rb, group, mask);
    return rb;
  }
};

static void teleport(World &w, btRigidBody *rb, const btTransform &t) {
  rb->setWorldTransform(t);
  rb->setInterpolationWorldTransform(t);
  if (!rb->isStaticOrKinematicObject()) rb->activate(true);
  w.dw->updateSingleAabb(rb);
}

// a chain robot: NJ revolute joints (alternating z / y axes), one box link body per joint
struct Robot {
  std::vector<btTransform> origin, pose;
  std::vector<btVector3> axis;
  std::vector<btRigidBody *> bodies;
  std::vector<double> q;
};
static const int NJ = 45;

static void fk(World &w, Robot &r, double *out) {
  btTransform t = btTransform::getIdentity();
  for (int j = 0; j < NJ; ++j) {
    t = t * r.origin[j];
    t.setBasis(t.getBasis() * btMatrix3x3(btQuaternion(r.axis[j], r.q[j])));
    r.pose[j] = t;
    teleport(w, r.bodies[j], t);
  }
  for (int j = 0; j < NJ; ++j) {
    btQuaternion qq = r.pose[j].getRotation();
    const btVector3 &p = r.pose[j].getOrigin();
    double *o = out + 7 * j;
    o[0] = p.x(); o[1] = p.y(); o[2] = p.z(); o[3] = qq.x(); o[4] = qq.y(); o[5] = qq.z(); o[6] = qq.w();
  }
}

// Counts touching pairs; like the shim's object contacts, it leaves out the links of the
// querying body's own robot (user index 1), whose self-collision is a separate, optional check.
struct Count : btCollisionWorld::ContactResultCallback {
  int n = 0;
  int self = 0;
  bool needsCollision(btBroadphaseProxy *proxy) const override {
    if (!ContactResultCallback::needsCollision(proxy)) return false;
    return !self || static_cast<btCollisionObject *>(proxy->m_clientObject)->getUserIndex() != self;
  }
  btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *, int, int,
                           const btCollisionObjectWrapper *, int, int) override {
    if (cp.getDistance() <= 0) ++n;
    return 0;
  }
};

int main(int argc, char **argv) {
  // "raw_bench teleport": only the teleport row (the interleaved rounds of native-bench.lisp)
  bool teleport_only = argc > 1 && std::string(argv[1]) == "teleport";
  btBoxShape link_shape(btVector3(0.02, 0.02, 0.04));
  btBoxShape small(btVector3(0.05, 0.05, 0.05));
  btStaticPlaneShape plane(btVector3(0, 0, 1), 0);
  World w;
  w.add(&plane, 0, btTransform::getIdentity(), 2, -1 ^ 2);
  std::vector<btRigidBody *> objs;
  for (int i = 0; i < 33; ++i)
    objs.push_back(w.add(&small, 1, btTransform(btQuaternion::getIdentity(),
                                                btVector3(1 + (i % 6) * 0.3, (i / 6) * 0.3 - 0.8, 0.05 + 0.12 * (i % 3))),
                         1, -1));
  Robot r;
  for (int j = 0; j < NJ; ++j) {
    r.origin.push_back(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, j == 0 ? 0.05 : 0.08)));
    r.axis.push_back(j % 2 ? btVector3(0, 1, 0) : btVector3(0, 0, 1));
    r.pose.push_back(btTransform::getIdentity());
    r.q.push_back(0);
    r.bodies.push_back(w.add(&link_shape, 0, btTransform::getIdentity(), 32, -1, true));
    r.bodies.back()->setUserIndex(1);
  }
  std::vector<double> out(7 * NJ);
  // the time of one teleport depends on where the body lies in memory (aliasing of loads and
  // stores): the median over 8 bodies
  std::vector<double> tels;
  for (int k = 0; k < 8; ++k) {
    btRigidBody *b = objs[k * 4];
    btTransform home = b->getWorldTransform();
    tels.push_back(per_call([&](int i) {
      teleport(w, b, btTransform(btQuaternion::getIdentity(), btVector3(1 + 1e-6 * (i % 100), 0, 1)));
    }, 100000));
    teleport(w, b, home);
  }
  std::sort(tels.begin(), tels.end());
  double t_tel = 0.5 * (tels[3] + tels[4]);
  if (teleport_only) {
    printf("teleport %.9g\n", t_tel);
    return 0;
  }
  // teleport, then the contacts of the moved body: the cycle of a projection step
  double t_telq = per_call([&](int i) {
    teleport(w, objs[5], btTransform(btQuaternion::getIdentity(), btVector3(1.6 + 1e-3 * (i % 2), -0.8, 0.05)));
    Count c;
    c.m_collisionFilterGroup = 1;
    c.m_collisionFilterMask = -1;
    w.dw->contactTest(objs[5], c);
  }, 50000);
  teleport(w, objs[5], btTransform(btQuaternion::getIdentity(), btVector3(1.6, -0.8, 0.05)));
  double t_fk = per_call([&](int i) {
    for (int j = 0; j < NJ; ++j) r.q[j] = 0.01 * ((i + j) % 20);
    fk(w, r, out.data());
  }, 20000);
  auto robot_contacts = [&] {  // contacts of every link with the world, own links left out
    Count c;
    c.self = 1;
    c.m_collisionFilterGroup = 32;
    c.m_collisionFilterMask = -1;
    for (auto *b : r.bodies) w.dw->contactTest(b, c);
    return c.n;
  };
  double t_col = per_call([&](int) { robot_contacts(); }, 5000);
  // new joint values, then the collision check of every link: the cycle of a motion check
  double t_fkcol = per_call([&](int i) {
    for (int j = 0; j < NJ; ++j) r.q[j] = 0.01 * ((i + j) % 20);
    fk(w, r, out.data());
    robot_contacts();
  }, 5000);
  double t_copy = per_call([&](int) {
    World c;
    auto &arr = w.dw->getCollisionObjectArray();
    for (int i = 0; i < arr.size(); ++i) {
      auto *s = btRigidBody::upcast(arr[i]);
      auto *rb = c.add(s->getCollisionShape(), s->getInvMass() > 0 ? 1 / s->getInvMass() : 0,
                       s->getWorldTransform(), s->getBroadphaseHandle()->m_collisionFilterGroup,
                       s->getBroadphaseHandle()->m_collisionFilterMask);
      rb->setCollisionFlags(s->getCollisionFlags());
      rb->setLinearVelocity(s->getLinearVelocity());
      rb->setAngularVelocity(s->getAngularVelocity());
    }
  }, 500);
  double t_sim = per_call([&](int) {
    World c;
    c.add(&plane, 0, btTransform::getIdentity(), 2, -1 ^ 2);
    for (int i = 0; i < 33; ++i)
      c.add(&small, 1, btTransform(btQuaternion::getIdentity(), btVector3((i % 6) * 0.3, (i / 6) * 0.3, 0.3 + 0.12 * (i % 3))), 1, -1);
    // the shim's loop: stop once every dynamic body sleeps or rested (< 1 cm/s, 0.1 rad/s)
    // for 0.1 s of simulated time
    double quiet = 0;
    for (int s = 0; s < 240; ++s) {
      bool awake = false, resting = true;
      auto &objs = c.dw->getCollisionObjectArray();
      for (int i = 0; i < objs.size(); ++i)
        if (!objs[i]->isStaticOrKinematicObject() && objs[i]->isActive()) awake = true;
      if (!awake) break;
      c.dw->stepSimulation(1.0 / 240, 0, 1.0 / 240);
      for (int i = 0; i < objs.size(); ++i) {
        auto *rb = btRigidBody::upcast(objs[i]);
        if (!rb || rb->isStaticOrKinematicObject() || !rb->isActive()) continue;
        if (rb->getLinearVelocity().length() >= 1e-2 || rb->getAngularVelocity().length() >= 1e-1)
          resting = false;
      }
      quiet = resting ? quiet + 1.0 / 240 : 0;
      if (quiet >= 0.1 - 1e-12) break;
    }
  }, 5);
  printf("teleport-contacts %.9g\njoints-collision %.9g\n", t_telq, t_fkcol);
  printf("teleport %.9g\njoints-and-poses %.9g\nrobot-collision %.9g\ncopy %.9g\nsimulate %.9g\n",
         t_tel, t_fk, t_col, t_copy, t_sim);
  return 0;
}

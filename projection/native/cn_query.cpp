// Contacts, closest distances, ignored pairs, ray batches and attachments.
#include "cn_internal.hpp"
#include "cn_sweep.hpp"

#include <algorithm>

namespace cn {

using PairKey = std::array<int, 4>;

static PairKey make_key(int oa, int la, int ob, int lb) {
  if (oa > ob || (oa == ob && la > lb)) return {ob, lb, oa, la};
  return {oa, la, ob, lb};
}

// Contact pairs as collected: one entry per contact point, merged by write_pairs.
using PairList = std::vector<std::pair<PairKey, double>>;

// The pair list of the running query, reused (queries run one at a time under the API lock
// and never nest), so that a query allocates nothing once it has run.
static PairList &scratch_pairs() {
  static PairList pairs;
  pairs.clear();
  return pairs;
}

// Sort PAIRS by key, keep the smallest distance of each pair, write up to CAP of them; return
// how many distinct pairs there are.
static int write_pairs(PairList &pairs, int *out4, double *dist, int cap) {
  std::sort(pairs.begin(), pairs.end());  // equal keys: smallest distance first
  int n = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (i > 0 && pairs[i].first == pairs[i - 1].first) continue;
    if (n < cap) {
      for (int k = 0; k < 4; ++k) out4[4 * n + k] = pairs[i].first[k];
      dist[n] = pairs[i].second;
    }
    ++n;
  }
  return n;
}

static void check_out(int cap, const void *a, const void *b) {
  check_output(cap, a, "pair output");
  check_output(cap, b, "distance output");
}

// Whether object OB is one of the N objects of EXCEPT.
static bool excepted(int ob, const int *except, int n) {
  for (int i = 0; i < n; ++i)
    if (except[i] == ob) return true;
  return false;
}

struct ObjectContacts : btCollisionWorld::ContactResultCallback {
  World &w;
  int self;
  double threshold;
  PairList &pairs;
  const int *except = nullptr;  // objects whose contacts are not looked for
  int n_except = 0;
  ObjectContacts(World &wd, int s, double t, PairList &p, int group, int mask)
      : w(wd), self(s), threshold(t), pairs(p) {
    m_collisionFilterGroup = group;
    m_collisionFilterMask = mask;
    m_closestDistanceThreshold = t > 0 ? t : 0;
  }
  bool needsCollision(btBroadphaseProxy *proxy) const override {
    if (!ContactResultCallback::needsCollision(proxy)) return false;
    auto *co = static_cast<btCollisionObject *>(proxy->m_clientObject);
    return co->getUserIndex() != self && !excepted(co->getUserIndex(), except, n_except);
  }
  btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *a, int, int,
                           const btCollisionObjectWrapper *b, int, int) override {
    if (cp.getDistance() > threshold) return 0;
    int oa, la, ob, lb;
    decode_rb(a->getCollisionObject(), oa, la);
    decode_rb(b->getCollisionObject(), ob, lb);
    if (oa != self) { std::swap(oa, ob); std::swap(la, lb); }
    if (w.pair_ignored(oa, la, ob, lb)) return 0;
    pairs.push_back({PairKey{oa, la, ob, lb}, (double)cp.getDistance()});
    return 0;
  }
};

struct PairDistance : btCollisionWorld::ContactResultCallback {
  const btCollisionObject *a;
  double best;
  btVector3 pa, pb;
  bool found = false;
  PairDistance(const btCollisionObject *ca, double maxd) : a(ca), best(maxd) {
    m_closestDistanceThreshold = maxd;
  }
  btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *w0, int, int,
                           const btCollisionObjectWrapper *, int, int) override {
    if (cp.getDistance() < best || !found) {
      if (cp.getDistance() > best) return 0;
      best = cp.getDistance();
      bool a_first = w0->getCollisionObject() == a;
      pa = a_first ? cp.getPositionWorldOnA() : cp.getPositionWorldOnB();
      pb = a_first ? cp.getPositionWorldOnB() : cp.getPositionWorldOnA();
      found = true;
    }
    return 0;
  }
};

// The objects whose boxes overlap the union of the boxes of the articulated object O's links,
// O itself and the objects of EXCEPT left out.
static std::vector<btBroadphaseProxy *> &articulated_neighbours(World &w, const Object &o,
                                                               const int *except, int n_except) {
  struct Others : btBroadphaseAabbCallback {
    int self;
    const int *except;
    int n_except;
    std::vector<btBroadphaseProxy *> *found;
    bool process(const btBroadphaseProxy *p) override {
      auto *co = static_cast<const btCollisionObject *>(p->m_clientObject);
      int ob = co->getUserIndex();
      if (ob != self && !excepted(ob, except, n_except))
        found->push_back(const_cast<btBroadphaseProxy *>(p));
      return true;
    }
  } others;
  static std::vector<btBroadphaseProxy *> found;  // reused: queries run one at a time
  found.clear();
  btVector3 lo, hi;
  if (!union_aabb(o, -1, lo, hi)) return found;
  others.self = o.id;
  others.except = except;
  others.n_except = n_except;
  others.found = &found;
  w.dw->getBroadphase()->aabbTest(lo, hi, others);
  return found;
}

// Calls TEST(link, rb, callback filter, other) for each link of O and each neighbour whose box
// overlaps the link's and that the link's collision filter accepts, until TEST returns true.
template <class Test>
static bool each_link_neighbour(World &w, const Object &o, const int *except, int n_except,
                                Test test) {
  std::vector<btBroadphaseProxy *> &found = articulated_neighbours(w, o, except, n_except);
  if (found.empty()) return false;
  for (size_t l = 0; l < o.link_rb.size(); ++l) {
    btRigidBody *rb = o.link_rb[l];
    if (!rb) continue;
    btVector3 a, b;
    rb->getCollisionShape()->getAabb(rb->getWorldTransform(), a, b);
    for (btBroadphaseProxy *p : found) {
      if (!TestAabbAgainstAabb2(a, b, p->m_aabbMin, p->m_aabbMax)) continue;
      if (test((int)l, rb, p)) return true;
    }
  }
  return false;
}

// Whether PROVEN_APART is asked (cn_set_contact_prefilter).
static bool g_contact_prefilter = true;

// Whether the link L of the articulated object O is farther from OTHER than Bullet's contact
// query could find them touching within THRESHOLD: the sweep checks' GJK (sweep::link_gap, never
// more than the distance) proves them more than THRESHOLD + 1 mm apart. The query, which builds
// and runs a collision algorithm for the pair, is then not asked: it finds nothing there (the
// two distances agree to a tenth of a millimetre where they meet).
static bool proven_apart(Object &o, int l, const btCollisionObject *other, double threshold) {
  const double maxd = threshold + 1e-3;
  return g_contact_prefilter && maxd > 0 && sweep::link_gap(o, l, other, maxd) >= maxd;
}

// Contacts of every link of the articulated object O with other objects: what contactTest of
// each link finds, from one broadphase query of the union of the links' boxes (instead of one
// tree query per link, most of whose hits would be the object's own links).
static void articulated_contacts(World &w, Object &o, double threshold, PairList &pairs,
                                 const int *except, int n_except) {
  each_link_neighbour(w, o, except, n_except, [&](int l, btRigidBody *rb, btBroadphaseProxy *p) {
    auto *bp = rb->getBroadphaseHandle();
    ObjectContacts cb(w, o.id, threshold, pairs, bp->m_collisionFilterGroup, bp->m_collisionFilterMask);
    auto *other = static_cast<btCollisionObject *>(p->m_clientObject);
    if (cb.needsCollision(p) && !proven_apart(o, l, other, threshold))
      w.dw->contactPairTest(rb, other, cb);
    return false;
  });
}

// What CN_OBJECT_FIRST_CONTACT leaves out besides the objects of except: links of the object
// (skip) and allowed (link, other, other link) triples, -2 standing for any.
struct ContactRules {
  const int *skip;
  int n_skip;
  const int *allowed;
  int n_allowed;
  bool skipped(int link) const {
    for (int i = 0; i < n_skip; ++i)
      if (skip[i] == link) return true;
    return false;
  }
  bool allowed_pair(int link, int other, int other_link) const {
    for (int i = 0; i < n_allowed; ++i) {
      const int *t = allowed + 3 * i;
      if ((t[0] == -2 || t[0] == link) && (t[1] == -2 || t[1] == other) &&
          (t[2] == -2 || t[2] == other_link))
        return true;
    }
    return false;
  }
};

// The first contact of SELF's links that the rules do not leave out.
struct FirstContact : btCollisionWorld::ContactResultCallback {
  World &w;
  int self;
  double threshold;
  const ContactRules &rules;
  bool found = false;
  PairKey key{};
  FirstContact(World &wd, int s, double t, const ContactRules &r) : w(wd), self(s), threshold(t), rules(r) {
    m_closestDistanceThreshold = t > 0 ? t : 0;
  }
  btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *a, int, int,
                           const btCollisionObjectWrapper *b, int, int) override {
    if (found || cp.getDistance() > threshold) return 0;
    int oa, la, ob, lb;
    decode_rb(a->getCollisionObject(), oa, la);
    decode_rb(b->getCollisionObject(), ob, lb);
    if (oa != self || (ob == self && lb < la)) { std::swap(oa, ob); std::swap(la, lb); }
    if (w.pair_ignored(oa, la, ob, lb) || rules.skipped(la) || rules.allowed_pair(la, ob, lb))
      return 0;
    found = true;
    key = PairKey{oa, la, ob, lb};
    return 0;
  }
};

static void check_link(const Object &o, int link) {
  if (o.kind == CN_BODY && link != -1)
    fail(CN_E_HANDLE, "link %d given for body %d, expected -1", link, o.id);
  if (o.kind == CN_ARTICULATED && (link < -1 || link >= (int)o.link_rb.size()))
    fail(CN_E_HANDLE, "link index %d out of range -1..%d in articulated object %d", link,
         (int)o.link_rb.size() - 1, o.id);
}

static bool reaches(World &w, int from, int target, int depth) {
  if (from == target) return true;
  if (depth > 32) return true;
  for (auto &a : w.attachments)
    if (a.obj == from && reaches(w, a.parent, target, depth + 1)) return true;
  return false;
}

static void restore_dynamic(World &w, Object &c) {
  if (!c.attached_kinematic || !c.rb) return;
  for (auto &a : w.attachments)
    if (a.obj == c.id && !a.loose) return;  // still rigidly held elsewhere
  c.rb->setCollisionFlags(c.rb->getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
  btVector3 in(0, 0, 0);
  c.shape->shape->calculateLocalInertia(c.mass, in);
  c.rb->setMassProps(c.mass, in);
  c.rb->updateInertiaTensor();
  c.rb->setGravity(w.dw->getGravity());
  c.rb->setLinearVelocity(btVector3(0, 0, 0));
  c.rb->setAngularVelocity(btVector3(0, 0, 0));
  c.rb->forceActivationState(ACTIVE_TAG);
  c.rb->activate(true);
  c.attached_kinematic = false;
}

}  // namespace cn

using namespace cn;

extern "C" {

int cn_object_local_aabb(int wh, int oh, int link, double *out) {
  return guard([&] {
    Object &o = world(wh).obj(oh);
    check_ptr(out, "AABB output");
    check_link_arg(o, oh, link);
    // each body's shapes, put into the frame of the object (or LINK): the box an upright
    // copy of it would have, whatever its pose now
    const btTransform inv = frame_pose(o, link).inverse();
    btVector3 lo(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT), hi = -lo;
    bool any = false;
    for_each_rb(o, [&](btRigidBody *rb, int l) {
      if (link >= 0 && l != link) return;
      btVector3 a, b;
      rb->getCollisionShape()->getAabb(inv * rb->getWorldTransform(), a, b);
      lo.setMin(a);
      hi.setMax(b);
      any = true;
    });
    if (!any) lo = hi = btVector3(0, 0, 0);
    out[0] = lo.x(); out[1] = lo.y(); out[2] = lo.z();
    out[3] = hi.x(); out[4] = hi.y(); out[5] = hi.z();
    return 0;
  });
}

int cn_world_contacts(int wh, double threshold, int *out4, double *dist, int cap) {
  return guard([&] {
    World &w = world(wh);
    check_finite(threshold, "contact threshold");
    check_out(cap, out4, dist);
    set_query_all(w, true);
    try {
      w.dw->performDiscreteCollisionDetection();  // updates every bounding box first
      forget_stale_aabbs(w);
    } catch (...) {
      set_query_all(w, false);
      throw;
    }
    set_query_all(w, false);
    PairList &pairs = scratch_pairs();
    btDispatcher *d = w.dw->getDispatcher();
    for (int i = 0; i < d->getNumManifolds(); ++i) {
      btPersistentManifold *m = d->getManifoldByIndexInternal(i);
      if (m->getNumContacts() == 0) continue;
      double md = BT_LARGE_FLOAT;
      for (int k = 0; k < m->getNumContacts(); ++k) md = std::min(md, (double)m->getContactPoint(k).getDistance());
      if (md > threshold) continue;
      int oa, la, ob, lb;
      decode_rb(m->getBody0(), oa, la);
      decode_rb(m->getBody1(), ob, lb);
      if (w.pair_ignored(oa, la, ob, lb)) continue;
      pairs.push_back({make_key(oa, la, ob, lb), md});
    }
    return write_pairs(pairs, out4, dist, cap);
  });
}

int cn_set_contact_prefilter(int on) {
  return guard([&] {
    int was = g_contact_prefilter ? 1 : 0;
    g_contact_prefilter = on != 0;
    return was;
  });
}

int cn_object_contacts(int wh, int oh, double threshold, int *out4, double *dist, int cap) {
  return cn_object_contacts_except(wh, oh, threshold, nullptr, 0, out4, dist, cap);
}

int cn_object_contacts_except(int wh, int oh, double threshold, const int *except, int n_except,
                              int *out4, double *dist, int cap) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    // an articulated object's own links are found by their shapes, not the broadphase: their
    // boxes may stay out of date for the next query that reads them
    if (o.kind == CN_ARTICULATED) sync_aabbs_except(w, [&](int ob) { return ob == oh; });
    else sync_aabbs(w);
    check_finite(threshold, "contact threshold");
    check_out(cap, out4, dist);
    if (n_except < 0) fail(CN_E_ARG, "%d objects to leave out, expected >= 0", n_except);
    if (n_except > 0) check_ptr(except, "objects to leave out");
    PairList &pairs = scratch_pairs();
    if (o.kind == CN_BODY) {
      auto *bp = o.rb->getBroadphaseHandle();
      ObjectContacts cb(w, oh, threshold, pairs, bp->m_collisionFilterGroup, bp->m_collisionFilterMask);
      cb.except = except;
      cb.n_except = n_except;
      w.dw->contactTest(o.rb, cb);
    } else {
      articulated_contacts(w, o, threshold, pairs, except, n_except);
    }
    if (o.kind == CN_ARTICULATED && o.self_collision) {
      for (size_t i = 0; i < o.link_rb.size(); ++i)
        for (size_t j = i + 1; j < o.link_rb.size(); ++j) {
          if (!o.link_rb[i] || !o.link_rb[j]) continue;
          const JointM *pj = nullptr;
          int a = (int)i, b = (int)j;
          int jb = o.model->links[b].parent_joint, ja = o.model->links[a].parent_joint;
          if ((jb >= 0 && o.model->joints[jb].parent == a) || (ja >= 0 && o.model->joints[ja].parent == b))
            continue;  // adjacent links always touch
          (void)pj;
          if (w.ignored.count(make_key(oh, a, oh, b))) continue;
          PairDistance pd(o.link_rb[i], threshold);
          w.dw->contactPairTest(o.link_rb[i], o.link_rb[j], pd);
          if (pd.found && pd.best <= threshold) pairs.push_back({PairKey{oh, a, oh, b}, pd.best});
        }
    }
    return write_pairs(pairs, out4, dist, cap);
  });
}

int cn_object_first_contact(int wh, int oh, double threshold, const int *except, int n_except,
                            const int *skip_links, int n_skip, const int *allowed3, int n_allowed,
                            int *out4) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh);
    if (o.kind != CN_ARTICULATED)
      fail(CN_E_ARG, "object %d is a plain body, expected an articulated object", oh);
    check_finite(threshold, "contact threshold");
    check_ptr(out4, "contact output");
    if (n_except < 0 || n_skip < 0 || n_allowed < 0)
      fail(CN_E_ARG, "counts %d, %d, %d of left-out objects, links and pairs, expected >= 0",
           n_except, n_skip, n_allowed);
    if (n_except > 0) check_ptr(except, "objects to leave out");
    if (n_skip > 0) check_ptr(skip_links, "links to leave out");
    if (n_allowed > 0) check_ptr(allowed3, "allowed contacts");
    sync_aabbs_except(w, [&](int ob) { return ob == oh; });
    ContactRules rules{skip_links, n_skip, allowed3, n_allowed};
    FirstContact cb(w, oh, threshold, rules);
    each_link_neighbour(w, o, except, n_except, [&](int l, btRigidBody *rb, btBroadphaseProxy *p) {
      if (rules.skipped(l)) return false;
      auto *bp = rb->getBroadphaseHandle();
      cb.m_collisionFilterGroup = bp->m_collisionFilterGroup;
      cb.m_collisionFilterMask = bp->m_collisionFilterMask;
      auto *other = static_cast<btCollisionObject *>(p->m_clientObject);
      if (cb.needsCollision(p) && !proven_apart(o, l, other, threshold))
        w.dw->contactPairTest(rb, other, cb);
      return cb.found;
    });
    if (!cb.found && o.self_collision) {
      for (size_t i = 0; i < o.link_rb.size() && !cb.found; ++i) {
        if (!o.link_rb[i] || rules.skipped((int)i)) continue;
        for (size_t j = i + 1; j < o.link_rb.size() && !cb.found; ++j) {
          if (!o.link_rb[j]) continue;
          int a = (int)i, b = (int)j;
          int jb = o.model->links[b].parent_joint, ja = o.model->links[a].parent_joint;
          if ((jb >= 0 && o.model->joints[jb].parent == a) || (ja >= 0 && o.model->joints[ja].parent == b))
            continue;  // adjacent links always touch
          if (w.ignored.count(make_key(oh, a, oh, b))) continue;
          PairDistance pd(o.link_rb[i], threshold);
          w.dw->contactPairTest(o.link_rb[i], o.link_rb[j], pd);
          if (pd.found && pd.best <= threshold && !rules.allowed_pair(a, oh, b)) {
            cb.found = true;
            cb.key = PairKey{oh, a, oh, b};
          }
        }
      }
    }
    if (cb.found)
      for (int k = 0; k < 4; ++k) out4[k] = cb.key[k];
    return cb.found ? 1 : 0;
  });
}

int cn_closest_distance(int wh, int oa, int la, int ob, int lb, double maxd, double *out7) {
  return guard([&] {
    World &w = world(wh);
    Object &a = w.obj(oa, "object A");
    Object &b = w.obj(ob, "object B");
    check_link(a, la);
    check_link(b, lb);
    check_positive(maxd, "maximum distance");
    check_ptr(out7, "distance output");
    double best = maxd;
    btVector3 pa(0, 0, 0), pb(0, 0, 0);
    bool found = false;
    for_each_rb(a, [&](btRigidBody *ra, int l1) {
      if (la >= 0 && l1 != la) return;
      for_each_rb(b, [&](btRigidBody *rb, int l2) {
        if (lb >= 0 && l2 != lb) return;
        if (ra == rb) return;
        PairDistance pd(ra, best);
        w.dw->contactPairTest(ra, rb, pd);
        if (pd.found && pd.best <= best) {
          best = pd.best;
          pa = pd.pa;
          pb = pd.pb;
          found = true;
        }
      });
    });
    out7[0] = best;
    for (int k = 0; k < 3; ++k) { out7[1 + k] = pa[k]; out7[4 + k] = pb[k]; }
    return found ? 1 : 0;
  });
}

int cn_ignore_pair(int wh, int oa, int la, int ob, int lb, int ignore) {
  return guard([&] {
    World &w = world(wh);
    check_link(w.obj(oa, "object A"), la);
    check_link(w.obj(ob, "object B"), lb);
    PairKey k = make_key(oa, la, ob, lb);
    if (ignore) w.ignored.insert(k);
    else w.ignored.erase(k);
    return 0;
  });
}

int cn_ray_test(int wh, const double *from, const double *to, int n, int *hit, double *out) {
  return guard([&] {
    World &w = world(wh);
    sync_aabbs(w);
    if (n < 0) fail(CN_E_ARG, "ray count %d, expected >= 0", n);
    if (n == 0) return 0;
    check_ptr(from, "ray start array");
    check_ptr(to, "ray end array");
    check_ptr(hit, "ray hit output");
    check_ptr(out, "ray result output");
    for (int i = 0; i < 3 * n; ++i) {
      if (!std::isfinite(from[i])) fail(CN_E_ARG, "ray %d start has %s in component %d", i / 3, num(from[i]).c_str(), i % 3);
      if (!std::isfinite(to[i])) fail(CN_E_ARG, "ray %d end has %s in component %d", i / 3, num(to[i]).c_str(), i % 3);
    }
    int hits = 0;
    for (int i = 0; i < n; ++i) {
      btVector3 f(from[3 * i], from[3 * i + 1], from[3 * i + 2]), t(to[3 * i], to[3 * i + 1], to[3 * i + 2]);
      btCollisionWorld::ClosestRayResultCallback cb(f, t);
      cb.m_collisionFilterGroup = -1;
      cb.m_collisionFilterMask = -1;
      if ((t - f).length2() > 0) w.dw->rayTest(f, t, cb);
      double *o = out + 7 * i;
      if (cb.hasHit()) {
        decode_rb(cb.m_collisionObject, hit[2 * i], hit[2 * i + 1]);
        o[0] = cb.m_closestHitFraction;
        for (int k = 0; k < 3; ++k) { o[1 + k] = cb.m_hitPointWorld[k]; o[4 + k] = cb.m_hitNormalWorld[k]; }
        ++hits;
      } else {
        hit[2 * i] = hit[2 * i + 1] = -1;
        o[0] = 1;
        for (int k = 0; k < 3; ++k) { o[1 + k] = t[k]; o[4 + k] = 0; }
      }
    }
    return hits;
  });
}

int cn_attach(int wh, int oh, int ph, int link, int loose) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh, "attached object");
    Object &p = w.obj(ph, "parent object");
    if (o.kind != CN_BODY) fail(CN_E_HANDLE, "object %d is an articulated object; only bodies can be attached", oh);
    if (p.kind == CN_ARTICULATED && link < 0)
      fail(CN_E_HANDLE, "attaching to articulated object %d needs a link index, got %d", ph, link);
    check_link(p, link);
    if (oh == ph) fail(CN_E_STATE, "object %d cannot be attached to itself", oh);
    if (reaches(w, ph, oh, 0))
      fail(CN_E_STATE, "attaching object %d to object %d would form a cycle", oh, ph);
    btTransform rel = frame_pose(p, link).inverse() * o.rb->getWorldTransform();
    bool found = false;
    for (auto &a : w.attachments)
      if (a.obj == oh && a.parent == ph && a.link == link) {
        a.loose = loose != 0;
        a.rel = rel;
        found = true;
      }
    if (!found) w.attachments.push_back({oh, ph, link, loose != 0, rel});
    if (!loose && !o.rb->isStaticOrKinematicObject()) {
      o.rb->setCollisionFlags(o.rb->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      o.rb->setMassProps(0, btVector3(0, 0, 0));
      o.rb->setLinearVelocity(btVector3(0, 0, 0));
      o.rb->setAngularVelocity(btVector3(0, 0, 0));
      o.rb->forceActivationState(DISABLE_DEACTIVATION);
      o.attached_kinematic = true;
    } else if (loose) {
      restore_dynamic(w, o);
    }
    return 0;
  });
}

int cn_detach(int wh, int oh, int ph) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh, "attached object");
    if (ph != -1) w.obj(ph, "parent object");
    size_t before = w.attachments.size();
    w.attachments.erase(std::remove_if(w.attachments.begin(), w.attachments.end(),
                                       [&](const Attachment &a) {
                                         return a.obj == oh && (ph == -1 || a.parent == ph);
                                       }),
                        w.attachments.end());
    restore_dynamic(w, o);
    return (int)(before - w.attachments.size());
  });
}

int cn_attachments(int wh, int *out4, int cap) {
  return guard([&] {
    World &w = world(wh);
    check_output(cap, out4, "attachment output");
    int n = 0;
    for (auto &a : w.attachments) {
      if (n < cap) {
        out4[4 * n] = a.obj;
        out4[4 * n + 1] = a.parent;
        out4[4 * n + 2] = a.link;
        out4[4 * n + 3] = a.loose ? 1 : 0;
      }
      ++n;
    }
    return n;
  });
}

int cn_robot_link_aabbs(int wh, int r, double *out, int cap) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    check_output(cap, out, "AABB output");
    int n = (int)o.link_rb.size();
    for (int l = 0; l < n && l < cap; ++l) {  // as cn_object_aabb gives each link's
      btVector3 lo, hi;
      if (!union_aabb(o, l, lo, hi)) lo = hi = frame_pose(o, l).getOrigin();
      double *b = out + 6 * l;
      b[0] = lo.x(); b[1] = lo.y(); b[2] = lo.z();
      b[3] = hi.x(); b[4] = hi.y(); b[5] = hi.z();
    }
    return n;
  });
}

}  // extern "C"

// The pieces of the sweep checks (cn_sweep.cpp): the swept hull shape, the distance callback,
// the moving bodies and the contacts found.
#pragma once
#include "cn_internal.hpp"

#include <BulletCollision/CollisionShapes/btConvexInternalShape.h>
#include <algorithm>
#include <cstring>

namespace cn {
namespace sweep {

// The convex hull of a convex shape at two placements (world coordinates), grown by `grow`.
class SweptHull : public btConvexInternalShape {
 public:
  const btConvexShape *child = nullptr;
  btTransform a, b;
  double grow = 0;
  SweptHull() { m_shapeType = CUSTOM_CONVEX_SHAPE_TYPE; }
  void set(const btConvexShape *c, const btTransform &ta, const btTransform &tb, double g) {
    child = c;
    a = ta;
    b = tb;
    grow = g;
    setMargin(c->getMargin() + g);
  }
  btVector3 localGetSupportingVertexWithoutMargin(const btVector3 &d) const override {
    btVector3 pa = a * child->localGetSupportingVertexWithoutMargin(d * a.getBasis());
    btVector3 pb = b * child->localGetSupportingVertexWithoutMargin(d * b.getBasis());
    return pa.dot(d) >= pb.dot(d) ? pa : pb;
  }
  void batchedUnitVectorGetSupportingVertexWithoutMargin(const btVector3 *v, btVector3 *out,
                                                         int n) const override {
    for (int i = 0; i < n; ++i) out[i] = localGetSupportingVertexWithoutMargin(v[i]);
  }
  void getAabb(const btTransform &t, btVector3 &lo, btVector3 &hi) const override {
    btVector3 l2, h2;
    child->getAabb(t * a, lo, hi);
    child->getAabb(t * b, l2, h2);
    lo.setMin(l2);
    hi.setMax(h2);
    btVector3 g(grow, grow, grow);
    lo -= g;
    hi += g;
  }
  void calculateLocalInertia(btScalar, btVector3 &inertia) const override {
    inertia.setValue(0, 0, 0);
  }
  const char *getName() const override { return "SweptHull"; }
};

// The smallest distance (and where) between a probe and one object, from contactPairTest.
struct Closest : btCollisionWorld::ContactResultCallback {
  double best;
  btVector3 point{0, 0, 0};
  bool found = false;
  explicit Closest(double maxd) : best(maxd) { m_closestDistanceThreshold = maxd > 0 ? maxd : 0; }
  btScalar addSingleResult(btManifoldPoint &cp, const btCollisionObjectWrapper *, int, int,
                           const btCollisionObjectWrapper *, int, int) override {
    double d = cp.getDistance();
    if (d <= best) {
      best = d;
      point = (cp.getPositionWorldOnA() + cp.getPositionWorldOnB()) * 0.5;
      found = true;
    }
    return 0;
  }
};

struct Piece {                    // one convex piece of a moving body, in the body frame
  const btConvexShape *shape;
  btTransform local;
  bool at_origin;                 // local is the identity
  // the piece's pose for the body's pose T (T itself when at_origin: the product would be T)
  btTransform placed(const btTransform &t) const { return at_origin ? t : t * local; }
};

struct Span {                     // a run of pieces held elsewhere
  const Piece *b = nullptr, *e = nullptr;
  const Piece *begin() const { return b; }
  const Piece *end() const { return e; }
};

// What a sweep needs of one robot link, the same in every call: kept per model.
// A compound shape's box as btCompoundShape::getAabb computes it, from its local box and margin
// kept aside (the shape itself is not read again: a check runs with cold caches).
struct CompoundBox {
  bool set = false;
  btVector3 centre{0, 0, 0}, half{0, 0, 0};  // its local box's centre; half extents with the margin
  void take(const btCompoundShape *c);
  void box(const btTransform &t, btVector3 &lo, btVector3 &hi) const {
    btMatrix3x3 abs_b = t.getBasis().absolute();
    btVector3 centre_w = t(centre);
    btVector3 extent = half.dot3(abs_b[0], abs_b[1], abs_b[2]);
    lo = centre_w - extent;
    hi = centre_w + extent;
  }
};

struct LinkInfo {
  const btCollisionShape *shape = nullptr;  // the link body's shape it was made for
  CompoundBox box;                          // its box, when it is a compound
  std::vector<int> chain;                   // movable joints from the root to the link
  std::array<uint64_t, 4> chain_bits{};     // the same as bits by joint index (the first 256)
  std::vector<Piece> pieces;
  double radius = 0;
};
struct ModelSweepInfo {
  std::vector<LinkInfo> links;
  std::vector<std::unique_ptr<btCollisionShape>> owned;  // boxes standing in for concave pieces
};

struct Rate {                     // a joint on a mover's chain, from the mover back to the base
  int joint;
  bool prismatic;
  double d, reach;                // its change over the move; bound on its origin's distance to the mover
};

struct Mover {                    // a moving robot link, attached object or body
  int obj = -1, link = -1;        // as reported
  const btCollisionObject *co = nullptr;
  int frame_link = -1;            // robot link it hangs from; -1: the base (or the body itself)
  btTransform rel;                // its frame relative to that link (or the base)
  const std::vector<int> *chain = nullptr;  // movable joints from the root to frame_link
  Span pieces;
  const CompoundBox *box = nullptr;  // its shape's box when kept aside (see aabb)
  // its shape's box at pose T, as the shape's getAabb gives it
  void aabb(const btTransform &t, btVector3 &lo, btVector3 &hi) const {
    if (box && box->set)
      box->box(t, lo, hi);
    else
      co->getCollisionShape()->getAabb(t, lo, hi);
  }
  int anchor = -1;                // last link on the chain a changing joint moves (-1: the base)
  int anchor_ix = 0;              // its entry in a slot's anchor poses (0: the base)
  btTransform rel_anchor;         // its frame relative to the anchor (or the base)
  double radius = 0;              // bound on |point - frame origin| over its shape
  double W = 0, B = 0;            // summed rotation and path-length bound over the whole move
  double A = 0;                   // a bound on its points' acceleration (<= 3 W B, see tighten_bounds)
  double Bp = 0;                  // a bound on its points' speed (<= B, which makes the grid)
  int r0 = 0, nr = 0;             // its chain's joint rates: entries r0 .. r0 + nr - 1 of Scratch::rates
  double reach = 0;               // bound on the distance of its points from the base origin
  // a box the mover stays in during the whole move, when one is known that is tighter than
  // its path bound (see Sweep::bound_movers)
  bool bounded = false;
  btVector3 bound_lo{0, 0, 0}, bound_hi{0, 0, 0};
  int c0 = 0, nc = 0;              // its candidates: entries c0 .. c0 + nc - 1 of the sweep's
};

struct Hit {
  int obj, link, hobj, hlink;
  double t;
  btVector3 point;
  bool operator<(const Hit &o) const {
    if (t != o.t) return t < o.t;
    return std::array<int, 4>{obj, link, hobj, hlink} < std::array<int, 4>{o.obj, o.link, o.hobj, o.hlink};
  }
};

// A body a mover may meet, with what the sweep knows of the pair, in one place (the tests of
// the time hierarchy read them together).
struct Cand {
  double lo[3], hi[3];  // the body's broadphase box
  double clear_until;   // the pair cannot touch before this time
  double dist, dist_max;  // the distance at sub-step point dist_k, searched up to dist_max
  int dist_k;           // (-1: none kept)
  int found;            // the body: entry of Scratch::found
  char done;            // reported, or left out as a start contact
  // whether the box LO HI meets the body's (TestAabbAgainstAabb2: touching boxes meet)
  // The distance at sub-step point K searched up to MAXD, as distance_at would give it, when
  // the one kept answers it; NaN otherwise.
  double kept_distance(int k, double maxd) const {
    if (dist_k != k) return NAN;
    if (dist < dist_max) return std::min(dist, maxd);  // the distance itself
    return maxd <= dist_max ? maxd : NAN;               // farther than dist_max
  }
  bool meets(const btVector3 &l, const btVector3 &h) const {
    return !(l.x() > hi[0] || h.x() < lo[0]) && !(l.y() > hi[1] || h.y() < lo[1]) &&
           !(l.z() > hi[2] || h.z() < lo[2]);
  }
};

// A table from times (doubles, compared by their bits) to entries, emptied in O(1) per sweep.
struct TimeIndex {
  std::vector<uint64_t> key;
  std::vector<uint32_t> gen;  // the key is set when its gen is the table's
  std::vector<size_t> val;
  uint32_t cur = 1;
  size_t used = 0;
  void clear() {
    if (++cur == 0) {  // wrapped: forget every entry for real
      std::fill(gen.begin(), gen.end(), 0);
      cur = 1;
    }
    used = 0;
  }
  static size_t hash(uint64_t k) { return (size_t)((k ^ (k >> 29)) * 0x9E3779B97F4A7C15ull >> 20); }
  // The entry of T, or SIZE_MAX when it has none.
  size_t find(double t) const {
    if (key.empty()) return SIZE_MAX;
    uint64_t k;
    std::memcpy(&k, &t, 8);
    for (size_t i = hash(k) & (key.size() - 1);; i = (i + 1) & (key.size() - 1)) {
      if (gen[i] != cur) return SIZE_MAX;
      if (key[i] == k) return val[i];
    }
  }
  void insert(double t, size_t v) {
    if (2 * (used + 1) > key.size()) grow();
    uint64_t k;
    std::memcpy(&k, &t, 8);
    size_t i = hash(k) & (key.size() - 1);
    while (gen[i] == cur) i = (i + 1) & (key.size() - 1);
    key[i] = k;
    gen[i] = cur;
    val[i] = v;
    ++used;
  }
  void grow() {
    std::vector<uint64_t> k2 = std::move(key);
    std::vector<uint32_t> g2 = std::move(gen);
    std::vector<size_t> v2 = std::move(val);
    size_t n = std::max<size_t>(64, 2 * k2.size());
    key.assign(n, 0);
    gen.assign(n, 0);
    val.assign(n, 0);
    uint32_t old = cur;
    cur = 1;
    used = 0;
    for (size_t i = 0; i < k2.size(); ++i)
      if (g2[i] == old) {
        double t;
        std::memcpy(&t, &k2[i], 8);
        insert(t, v2[i]);
      }
  }
};

// The working arrays of the sweeps, kept from one call to the next so that a check does not
// allocate them afresh (each use sets the size it needs and every entry it reads). One for the
// process: the library's entry points run one at a time (the API lock), from whatever thread.
struct Scratch {
  std::vector<double> q0, q1, qt, dv;
  std::vector<Mover> movers;
  std::vector<int> moving_ids;
  std::vector<Hit> hits;
  std::vector<char> needed;
  std::vector<btTransform> lp, lp0, lp1, slot_pose;
  std::vector<const btCollisionObject *> found;
  std::vector<btVector3> found_lo, found_hi, mlo, mhi, slot_lo, slot_hi;
  std::vector<Cand> cand;
  std::vector<std::array<int, 4>> found_id;
  std::vector<double> fb[6];  // the found boxes by coordinate: lo x y z, hi x y z
  std::vector<int> meets;     // the found boxes one move box meets
  std::vector<int> point_slot;
  std::vector<Rate> rates;
  std::vector<std::array<int, 2>> mine_ignored;  // gather_candidates: one mover's ignore records
  std::vector<int> fk_joints, fk_moving;  // see Sweep::fk
  std::vector<char> moved;
  std::vector<int> anchors;               // the movers' distinct anchors
  std::vector<btTransform> time_poses;    // per time: the base, then the anchors' poses
  TimeIndex time_index;
  std::vector<size_t> slot_at;            // per slot: its entry in time_poses
  std::vector<char> slot_have;            // per slot and mover: pose and box computed
  std::vector<std::vector<int>> pool;
};

// Bullet's bounding radius of a shape about its frame origin (from its local box).
inline double shape_radius(const btCollisionShape *s) {
  btVector3 lo, hi;
  s->getAabb(btTransform::getIdentity(), lo, hi);
  double r2 = 0;
  for (int k = 0; k < 8; ++k) {
    btVector3 c((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    r2 = std::max(r2, (double)c.length2());
  }
  return std::sqrt(r2);
}

// The movable joints on the way from the root to LINK, root first.
inline void link_chain(const Model &m, int link, std::vector<int> &out) {
  out.clear();
  for (int l = link; l >= 0;) {
    int pj = m.links[l].parent_joint;
    if (pj < 0) break;
    int type = m.joints[pj].type;
    if (type == CN_JOINT_REVOLUTE || type == CN_JOINT_CONTINUOUS || type == CN_JOINT_PRISMATIC)
      out.push_back(pj);
    l = m.joints[pj].parent;
  }
  std::reverse(out.begin(), out.end());
}

// The smallest distance, searched up to MAXD (MAXD when nothing is nearer), between the convex
// A at TA and the collision object OTHER; <= 0 when they touch (not a penetration depth).
double convex_distance(const btConvexShape *a, const btTransform &ta, const btCollisionObject *other,
                       double maxd);

// The distance of a body's convex PIECES, the body at pose T, from the collision object OTHER:
// the smallest convex_distance of a piece, searched up to MAXD (MAXD when farther), stopping at
// the first piece that touches (<= 0).
template <class Pieces>
double pieces_distance(const Pieces &pieces, const btTransform &t, const btCollisionObject *other,
                       double maxd) {
  double d = maxd;
  for (const Piece &p : pieces) {
    d = std::min(d, convex_distance(p.shape, p.placed(t), other, d));
    if (d <= 0) break;
  }
  return d;
}

// Whether the convex A (at TA; null: A's frame is the world's) may touch the collision object
// OTHER: false only when every piece of OTHER near A is proven apart from it (an axis with a
// gap between their support points), true otherwise.
bool may_touch(const btConvexShape *a, const btTransform *ta, const btCollisionObject *other);
// The same for A in the world's frame whose box there (as its getAabb gives it for the
// identity) is known: LO HI.
bool may_touch(const btConvexShape *a, const btVector3 &lo, const btVector3 &hi,
               const btCollisionObject *other);

// The distance of link LINK (with a body) of the articulated object O, where it is, from the
// collision object OTHER, as convex_distance finds it over the link's convex pieces (a mesh
// piece stands in as its box): never more than the distance; MAXD when nothing is nearer.
double link_gap(Object &o, int link, const btCollisionObject *other, double maxd);

}  // namespace sweep
}  // namespace cn

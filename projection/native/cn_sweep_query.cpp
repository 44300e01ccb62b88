// Distances for the sweep checks: GJK on the cores of convex pieces (margins added back), over
// the children of compounds and the triangles of meshes near the probe, stopping at the first
// touch. No penetration depth is computed: the sweep checks only ask how far apart, or whether
// touching, which Bullet's contact queries answer with EPA and a contact manifold per pair.
#include "cn_sweep.hpp"

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

namespace cn {
namespace sweep {
namespace {

struct Query {
  const btConvexShape *a;
  btTransform ta;
  btVector3 lo, hi;   // the probe's box grown by the search distance
  double maxd;        // the search distance
  double best;        // the smallest distance so far (maxd: nothing nearer)
};

void against_convex(Query &q, const btConvexShape *b, const btTransform &tb) {
  btGjkEpaSolver2::sResults r;
  btVector3 guess = tb.getOrigin() - q.ta.getOrigin();
  if (guess.length2() < 1e-12) guess.setValue(1, 0, 0);
  double margins = q.a->getMargin() + b->getMargin();
  double d = btGjkEpaSolver2::Distance(q.a, q.ta, b, tb, guess, r) ? r.distance - margins : -margins;
  q.best = std::min(q.best, d);
}

struct Triangles : btTriangleCallback {
  Query *q;
  btTransform tb;
  double margin;
  void processTriangle(btVector3 *v, int, int) override {
    if (q->best <= 0) return;
    btTriangleShape tri(v[0], v[1], v[2]);
    tri.setMargin(margin);
    against_convex(*q, &tri, tb);
  }
};

void against_shape(Query &q, const btCollisionShape *b, const btTransform &tb) {
  if (q.best <= 0) return;
  if (b->isCompound()) {
    auto *c = static_cast<const btCompoundShape *>(b);
    for (int i = 0; i < c->getNumChildShapes() && q.best > 0; ++i) {
      btTransform t = tb * c->getChildTransform(i);
      btVector3 lo, hi;
      c->getChildShape(i)->getAabb(t, lo, hi);
      if (TestAabbAgainstAabb2(lo, hi, q.lo, q.hi)) against_shape(q, c->getChildShape(i), t);
    }
  } else if (b->isConvex()) {
    against_convex(q, static_cast<const btConvexShape *>(b), tb);
  } else if (b->getShapeType() == STATIC_PLANE_PROXYTYPE) {
    auto *p = static_cast<const btStaticPlaneShape *>(b);
    btVector3 n = tb.getBasis() * p->getPlaneNormal();
    double c = p->getPlaneConstant() + n.dot(tb.getOrigin());
    btVector3 deepest = q.ta * q.a->localGetSupportingVertex(-(n * q.ta.getBasis()));
    q.best = std::min(q.best, (double)n.dot(deepest) - c - p->getMargin());
  } else if (b->isConcave()) {
    // the triangles near the probe, in the mesh's frame
    btTransform inv = tb.inverse();
    btVector3 lo, hi;
    q.a->getAabb(inv * q.ta, lo, hi);
    btVector3 g(q.maxd, q.maxd, q.maxd);
    lo -= g;
    hi += g;
    Triangles cb;
    cb.q = &q;
    cb.tb = tb;
    cb.margin = b->getMargin();
    static_cast<const btConcaveShape *>(b)->processAllTriangles(&cb, lo, hi);
  }
}

}  // namespace

double convex_distance(const btConvexShape *a, const btTransform &ta, const btCollisionObject *other,
                       double maxd) {
  Query q;
  q.a = a;
  q.ta = ta;
  q.maxd = maxd;
  q.best = maxd;
  a->getAabb(ta, q.lo, q.hi);
  btVector3 g(maxd, maxd, maxd);
  q.lo -= g;
  q.hi += g;
  against_shape(q, other->getCollisionShape(), other->getWorldTransform());
  return q.best;
}

}  // namespace sweep
}  // namespace cn

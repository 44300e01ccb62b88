// Distances for the sweep checks: GJK on the cores of convex pieces (margins added back), over
// the children of compounds and the triangles of meshes near the probe, stopping at the first
// touch. No penetration depth is computed: the sweep checks only ask how far apart, or whether
// touching, which Bullet's contact queries answer with EPA and a contact manifold per pair.
// The GJK is this file's own: Bullet's (btGjkEpaSolver2::Distance) stops when a support point
// repeats one of the last four, which on boxes leaves it on a face that is not the nearest
// about once in a hundred queries, the distance then too large by up to centimetres. Here the
// search ends only when the simplex cannot shrink, and its value is the gap its support
// planes prove: never more than the distance.
#include "cn_sweep.hpp"

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>

namespace cn {
namespace sweep {
namespace {

// A convex shape placed in the world: its support point (core, without margin) in a world
// direction.
struct Placed {
  const btConvexShape *s;
  const btTransform *t;  // null: the shape's own frame is the world's
  btVector3 support(const btVector3 &d) const {
    if (!t) return s->localGetSupportVertexWithoutMarginNonVirtual(d);
    return *t * s->localGetSupportVertexWithoutMarginNonVirtual(d * t->getBasis());
  }
};

// The point of the simplex S (N points, the newest last) nearest the origin, with S reduced to
// the smallest face that holds it; N becomes 0 when the simplex (a tetrahedron) holds the origin.
btVector3 nearest_on_segment(btVector3 *s, int &n) {
  const btVector3 &a = s[0], &b = s[1];
  btVector3 ab = b - a;
  double t = -a.dot(ab), l2 = ab.length2();
  if (t <= 0 || l2 <= 0) {
    n = 1;
    return a;
  }
  if (t >= l2) {
    s[0] = b;
    n = 1;
    return b;
  }
  return a + ab * (t / l2);
}

btVector3 nearest_on_triangle(btVector3 *s, int &n) {
  // the regions of the triangle a b c around the origin p (Ericson, Real-Time Collision
  // Detection, 5.1.5)
  btVector3 a = s[0], b = s[1], c = s[2];
  // the simplex shrinks to the vertex or the edge whose region holds the nearest point
  auto vertex = [&](const btVector3 &v) {
    s[0] = v;
    n = 1;
    return v;
  };
  auto edge = [&](const btVector3 &u, const btVector3 &v, const btVector3 &at) {
    s[0] = u;
    s[1] = v;
    n = 2;
    return at;
  };
  btVector3 ab = b - a, ac = c - a, ap = -a;
  double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return vertex(a);
  btVector3 bp = -b;
  double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return vertex(b);
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return edge(a, b, a + ab * (d1 / (d1 - d3)));
  btVector3 cp = -c;
  double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return vertex(c);
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return edge(a, c, a + ac * (d2 / (d2 - d6)));
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return edge(b, c, b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  double den = va + vb + vc;
  if (!(den > 0)) {  // degenerate: the nearest of its edges
    btVector3 e[3][2] = {{a, b}, {a, c}, {b, c}};
    btVector3 best(0, 0, 0);
    double bd = -1;
    btVector3 keep[2];
    int kn = 0;
    for (auto &ed : e) {
      btVector3 t2[2] = {ed[0], ed[1]};
      int m = 2;
      btVector3 q = nearest_on_segment(t2, m);
      if (bd < 0 || q.length2() < bd) {
        bd = q.length2();
        best = q;
        keep[0] = t2[0];
        keep[1] = t2[1];
        kn = m;
      }
    }
    for (int i = 0; i < kn; ++i) s[i] = keep[i];
    n = kn;
    return best;
  }
  double v = vb / den, w = vc / den;
  return a + ab * v + ac * w;
}

btVector3 nearest_on_tetrahedron(btVector3 *s, int &n) {
  // the faces the origin is not inside of (the fourth vertex not strictly on its side; all of
  // them when the tetrahedron is flat, which holds nothing), each with the vertex left out
  static const int face[4][4] = {{0, 1, 2, 3}, {0, 3, 1, 2}, {0, 2, 3, 1}, {1, 3, 2, 0}};
  btVector3 best(0, 0, 0);
  double bd = -1;
  btVector3 keep[3];
  int kn = 0;
  double scale = std::max({(s[1] - s[0]).length(), (s[2] - s[0]).length(), (s[3] - s[0]).length()});
  bool flat = std::fabs((s[1] - s[0]).dot((s[2] - s[0]).cross(s[3] - s[0]))) <= 1e-12 * scale * scale * scale;
  for (const auto &f : face) {
    const btVector3 &a = s[f[0]], &b = s[f[1]], &c = s[f[2]], &d = s[f[3]];
    btVector3 nrm = (b - a).cross(c - a);
    double so = -a.dot(nrm), sd = (d - a).dot(nrm);
    if (!flat && so * sd > 0) continue;  // the origin is on the fourth vertex's side
    btVector3 t3[3] = {a, b, c};
    int m = 3;
    btVector3 q = nearest_on_triangle(t3, m);
    if (bd < 0 || q.length2() < bd) {
      bd = q.length2();
      best = q;
      for (int i = 0; i < m; ++i) keep[i] = t3[i];
      kn = m;
    }
  }
  if (bd < 0) {  // inside every face
    n = 0;
    return btVector3(0, 0, 0);
  }
  for (int i = 0; i < kn; ++i) s[i] = keep[i];
  n = kn;
  return best;
}

// The distance between the cores of A and B less R (their margins, so <= 0 when they touch),
// searched up to MAXD: MAXD when it is farther, -R when the cores overlap. GJK from the search
// direction V on, with the gap its support planes prove (every point x of A - B has
// v.x >= v.w for the support point w along -v) as the value: the distance itself once the
// search converges, a lower bound where it stops early. With TOUCH_ENOUGH the search also
// stops as soon as the cores are found within R (a value <= 0, not the distance).
double gap(const Placed &a, const Placed &b, double r, double maxd, btVector3 v, bool touch_enough) {
  btVector3 s[4];
  int n = 0;
  double lower = -BT_LARGE_FLOAT;
  if (!(v.length2() > 1e-24)) v.setValue(1, 0, 0);
  for (int it = 0; it < 64; ++it) {
    btVector3 w = a.support(-v) - b.support(v);  // the point of A - B furthest along -v
    double vl = v.length();
    lower = std::max(lower, v.dot(w) / vl);  // proven: no point of A - B nearer
    if (lower - r >= maxd) return maxd;
    if (n > 0 && vl - lower <= 1e-12 + 1e-10 * vl) break;  // converged: v is the nearest point
    bool seen = false;
    for (int i = 0; i < n; ++i) seen |= s[i] == w;
    if (seen) break;                             // the simplex cannot shrink further
    s[n++] = w;
    switch (n) {
      case 1: v = w; break;
      case 2: v = nearest_on_segment(s, n); break;
      case 3: v = nearest_on_triangle(s, n); break;
      default: v = nearest_on_tetrahedron(s, n); break;
    }
    // the cores overlap, or so it seems where the simplex has grown flat: a proven gap wins
    if (n == 0 || v.length2() < 1e-24) return lower > 0 ? std::min(maxd, lower - r) : -r;
    if (touch_enough && v.length2() <= r * r) return std::min(0.0, lower - r);
  }
  return std::min(maxd, std::max(-r, lower - r));
}


// A query of the distance from the convex A to a collision object's pieces near it.
struct Query {
  Placed a;
  double margin;        // A's
  btVector3 lo, hi;     // A's box grown by the search distance
  btVector3 centre;     // the centre of A's box: the first search direction points from there
  double maxd;          // the search distance
  double best;          // the smallest distance so far (maxd: nothing nearer)
  bool touch_enough;    // a touch ends the search (the distance is not needed)
};

void against_convex(Query &q, const btConvexShape *b, const btTransform &tb, const btVector3 &bcentre) {
  Placed pb{b, &tb};
  q.best = std::min(q.best, gap(q.a, pb, q.margin + b->getMargin(), q.best, q.centre - bcentre, q.touch_enough));
}

struct Triangles : btTriangleCallback {
  Query *q;
  btTransform tb;
  double margin;
  void processTriangle(btVector3 *v, int, int) override {
    if (q->best <= 0) return;
    btTriangleShape tri(v[0], v[1], v[2]);
    tri.setMargin(margin);
    against_convex(*q, &tri, tb, tb * ((v[0] + v[1] + v[2]) / 3));
  }
};

void against_shape(Query &q, const btCollisionShape *b, const btTransform &tb) {
  if (q.best <= 0) return;
  if (b->isCompound()) {
    auto *c = static_cast<const btCompoundShape *>(b);
    for (int i = 0; i < c->getNumChildShapes() && q.best > 0; ++i) {
      const btCollisionShape *child = c->getChildShape(i);
      btTransform t = tb * c->getChildTransform(i);
      btVector3 lo, hi;
      child->getAabb(t, lo, hi);
      if (!TestAabbAgainstAabb2(lo, hi, q.lo, q.hi)) continue;
      if (child->isConvex())
        against_convex(q, static_cast<const btConvexShape *>(child), t, (lo + hi) * 0.5);
      else
        against_shape(q, child, t);
    }
  } else if (b->isConvex()) {
    btVector3 lo, hi;
    b->getAabb(tb, lo, hi);
    if (TestAabbAgainstAabb2(lo, hi, q.lo, q.hi))
      against_convex(q, static_cast<const btConvexShape *>(b), tb, (lo + hi) * 0.5);
  } else if (b->getShapeType() == STATIC_PLANE_PROXYTYPE) {
    auto *p = static_cast<const btStaticPlaneShape *>(b);
    btVector3 n = tb.getBasis() * p->getPlaneNormal();
    double c = p->getPlaneConstant() + n.dot(tb.getOrigin());
    btVector3 deepest = q.a.support(-n) - n * q.margin;
    q.best = std::min(q.best, (double)n.dot(deepest) - c - p->getMargin());
  } else if (b->isConcave()) {
    // the triangles near A, in the mesh's frame
    btTransform inv = tb.inverse();
    btVector3 lo, hi;
    q.a.s->getAabb(q.a.t ? inv * *q.a.t : inv, lo, hi);
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

// The query of A (at TA; null: A's frame is the world's) whose box there is LO HI.
double query(const btConvexShape *a, const btTransform *ta, const btVector3 &lo, const btVector3 &hi,
             const btCollisionObject *other, double maxd, bool touch_enough) {
  Query q;
  q.a = {a, ta};
  q.margin = a->getMargin();
  q.lo = lo;
  q.hi = hi;
  q.centre = (q.lo + q.hi) * 0.5;
  btVector3 g(maxd, maxd, maxd);
  q.lo -= g;
  q.hi += g;
  q.maxd = maxd;
  q.best = maxd;
  q.touch_enough = touch_enough;
  against_shape(q, other->getCollisionShape(), other->getWorldTransform());
  return q.best;
}

}  // namespace

double convex_distance(const btConvexShape *a, const btTransform &ta, const btCollisionObject *other,
                       double maxd) {
  btVector3 lo, hi;
  a->getAabb(ta, lo, hi);
  return query(a, &ta, lo, hi, other, maxd, false);
}

namespace {
// MAY_TOUCH of A (at TA; null: A's frame is the world's) whose box there is LO HI: apart only by
// a proven gap, of more than rounding.
bool touch_query(const btConvexShape *a, const btTransform *ta, const btVector3 &lo,
                 const btVector3 &hi, const btCollisionObject *other) {
  return query(a, ta, lo, hi, other, 1e-10, true) < 1e-10;
}
}  // namespace

bool may_touch(const btConvexShape *a, const btTransform *ta, const btCollisionObject *other) {
  btVector3 lo, hi;
  a->getAabb(ta ? *ta : btTransform::getIdentity(), lo, hi);
  return touch_query(a, ta, lo, hi, other);
}

bool may_touch(const btConvexShape *a, const btVector3 &lo, const btVector3 &hi,
               const btCollisionObject *other) {
  return touch_query(a, nullptr, lo, hi, other);
}

}  // namespace sweep
}  // namespace cn

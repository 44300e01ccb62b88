// Self-test of the sweep checks' distances (cn_sweep_query.cpp: convex_distance, may_touch)
// against Bullet's own GJK, on seeded random pairs of boxes, convex hulls, cylinders, spheres
// and swept hulls, placed far from the world's origin as the kitchen's pieces are. Bullet's
// btGjkEpaSolver2::Distance gives the distance of two actual points, so never less than the
// true distance; its smallest value over many start directions is taken as the truth (from one
// start direction alone it is sometimes centimetres too large). Internal functions: built against
// the library's headers, run by `make check`.
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "../cn_sweep.hpp"
#include "cn_test.h"

using namespace cn::sweep;

static std::mt19937 rng(5);
static double u(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

static btQuaternion random_rotation() {
  btVector3 axis(u(-1, 1), u(-1, 1), u(-1, 1));
  if (axis.length2() < 1e-6) axis.setValue(0, 0, 1);
  return btQuaternion(axis.normalized(), u(-3.2, 3.2));
}

// A random convex shape (kind 0 box, 1 hull, 2 cylinder, 3 sphere) of size about S.
static std::unique_ptr<btConvexShape> random_shape(int kind, double s) {
  std::unique_ptr<btConvexShape> out;
  if (kind == 0) {
    out.reset(new btBoxShape(btVector3(u(0.1, 1) * s, u(0.1, 1) * s, u(0.1, 1) * s)));
  } else if (kind == 1) {
    auto *h = new btConvexHullShape();
    for (int i = 0; i < 12; ++i) h->addPoint(btVector3(u(-1, 1) * s, u(-1, 1) * s, u(-1, 1) * s), false);
    h->recalcLocalAabb();
    out.reset(h);
  } else if (kind == 2) {
    double radius = u(0.2, 1) * s;
    out.reset(new btCylinderShapeZ(btVector3(radius, radius, u(0.2, 1) * s)));
  } else {
    out.reset(new btSphereShape(u(0.2, 1) * s));
  }
  if (kind < 3) out->setMargin(kind == 2 ? 0.004 : 0.001);
  return out;
}

// The smallest of Bullet's distances (margins taken off) over many start directions; false when
// Bullet finds the cores overlapping.
static bool bullet_distance(const btConvexShape *a, const btTransform &ta, const btConvexShape *b,
                            const btTransform &tb, double &d) {
  double best = BT_LARGE_FLOAT;
  for (int k = 0; k < 26; ++k) {
    btVector3 guess = k == 0 ? tb.getOrigin() - ta.getOrigin() : btVector3(u(-1, 1), u(-1, 1), u(-1, 1));
    btGjkEpaSolver2::sResults r;
    if (!btGjkEpaSolver2::Distance(a, ta, b, tb, guess, r)) return false;
    best = std::min(best, (double)r.distance);
  }
  d = best - a->getMargin() - b->getMargin();
  return true;
}

int main() {
  const btVector3 far(3.7, -2.2, 0.9);
  int compared = 0, touching = 0, bullet_once_off = 0, not_proven_apart = 0;
  double worst_over = 0, worst_under = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    int ka = trial % 4, kb = (trial / 4) % 3;
    std::unique_ptr<btConvexShape> a = random_shape(ka, 0.08), b = random_shape(kb, 0.2);
    btTransform tb(random_rotation(), far + btVector3(u(-0.1, 0.1), u(-0.1, 0.1), u(-0.1, 0.1)));
    btTransform ta(random_rotation(), tb.getOrigin() + btVector3(u(-1, 1), u(-1, 1), u(-1, 1)) * 0.35);
    // half the pairs as a swept hull of A between TA and a second placement
    SweptHull hull;
    const btConvexShape *probe = a.get();
    btTransform tprobe = ta;
    if (trial % 2) {
      btTransform ta2(random_rotation(), ta.getOrigin() + btVector3(u(-1, 1), u(-1, 1), u(-1, 1)) * 0.1);
      hull.set(a.get(), ta, ta2, u(0, 0.003));
      probe = &hull;
      tprobe.setIdentity();
    }
    btCollisionObject other;
    other.setCollisionShape(b.get());
    other.setWorldTransform(tb);
    double ref;
    bool apart_cores = bullet_distance(probe, tprobe, b.get(), tb, ref);
    double mine = convex_distance(probe, tprobe, &other, 10.0);
    bool touch = may_touch(probe, trial % 2 ? nullptr : &tprobe, &other);
    if (!apart_cores) {  // the cores overlap
      CHECK(mine <= 0);
      CHECK(touch);
      ++touching;
      continue;
    }
    ++compared;
    // never more than a distance Bullet finds between two points of the shapes
    worst_over = std::max(worst_over, mine - ref);
    worst_under = std::max(worst_under, ref - mine);
    if (ref <= -1e-9) {
      ++touching;
      CHECK(mine <= 0);
      CHECK(touch);
    }
    if (ref >= 1e-6 && touch) ++not_proven_apart;
    // the search up to a smaller distance: that distance when farther, else the same value
    double capped = convex_distance(probe, tprobe, &other, 0.01);
    CHECK(ref > 0.01 + 1e-9 ? capped == 0.01 : std::fabs(capped - std::min(mine, 0.01)) < 1e-9);
    btGjkEpaSolver2::sResults r1;
    if (btGjkEpaSolver2::Distance(probe, tprobe, b.get(), tb, tb.getOrigin() - tprobe.getOrigin(), r1) &&
        r1.distance - probe->getMargin() - b->getMargin() > ref + 1e-6)
      ++bullet_once_off;
  }
  // a compound's box kept aside (CompoundBox) is the one its getAabb computes, to the bit
  int boxes_differ = 0;
  for (int trial = 0; trial < 500; ++trial) {
    btCompoundShape c;
    std::vector<std::unique_ptr<btConvexShape>> kids;
    for (int k = 0; k < 1 + trial % 3; ++k) {
      kids.push_back(random_shape(trial % 4, 0.1));
      c.addChildShape(btTransform(random_rotation(), btVector3(u(-0.2, 0.2), u(-0.2, 0.2), u(-0.2, 0.2))), kids.back().get());
    }
    c.setMargin(u(0, 0.01));
    CompoundBox kept;
    kept.take(&c);
    btTransform t(random_rotation(), far + btVector3(u(-1, 1), u(-1, 1), u(-1, 1)));
    btVector3 lo, hi, klo, khi;
    c.getAabb(t, lo, hi);
    kept.box(t, klo, khi);
    for (int k = 0; k < 3; ++k)
      if (std::memcmp(&lo[k], &klo[k], sizeof(double)) || std::memcmp(&hi[k], &khi[k], sizeof(double))) {
        ++boxes_differ;
        break;
      }
  }
  CHECK(boxes_differ == 0);
  CHECK(worst_over < 1e-9);
  CHECK(worst_under < 1e-7);
  CHECK(not_proven_apart == 0);
  CHECK(touching > 100 && compared > 3000);
  printf("cn_gjk_check: %d checks, %d failed (%d pairs compared, %d touching; Bullet's GJK from "
         "one start direction too far on %d; largest difference %.2g m)\n",
         checks, failures, compared, touching, bullet_once_off, std::max(worst_over, worst_under));
  return failures ? 1 : 0;
}

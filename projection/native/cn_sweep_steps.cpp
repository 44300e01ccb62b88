// Sweep checks, the search over the sub-steps (struct Sweep of cn_sweep_impl.hpp; the setup and
// the entry points are in cn_sweep.cpp): the candidates each mover may meet, the time hierarchy
// descended by halving, and the confirmation of a touching hull by distances.
//
// A sub-step that may hold a contact is searched by halving the interval on distances: an
// interval whose pieces cannot reach the object (distance at its start beyond its path bound,
// or its hull apart from it) is clear, one whose start is at or below distance 0 is the first
// contact. A pair is reported only where the computed distance is <= 0 and Bullet's contact
// query (the discrete checks') agrees, and missed only when it never penetrates deeper than
// `tolerance`; the contact query is asked only there, for its verdict and the contact point. The sub-steps (a power of two) are visited from the whole move down by halving,
// each mover's box over an interval sorting out the candidates it can meet there; a pair found
// apart by d is not looked at again before the move could have closed d (conservative
// advancement).
#include "cn_sweep_impl.hpp"

namespace cn {
namespace sweep {

// The box mover M can reach anywhere on its way from T0 to T1: its box at the start grown by
// its path bound, cut down to the box of its two end boxes grown by the chord bound.
void Sweep::move_box(const Mover &m, const btTransform &t0, const btTransform &t1, btVector3 &lo,
                     btVector3 &hi) const {
  btVector3 lo0, hi0, lo1, hi1;
  m.aabb(t0, lo0, hi0);
  m.aabb(t1, lo1, hi1);
  double dev = std::min(m.B, 3 * m.W * m.B / 8);
  btVector3 g(dev, dev, dev), p(m.B, m.B, m.B);
  lo = lo0;
  hi = hi0;
  lo.setMin(lo1);
  hi.setMax(hi1);
  lo -= g;
  hi += g;
  lo.setMax(lo0 - p);
  hi.setMin(hi0 + p);
}

// Every mover's candidates: the bodies (not the robot's, not carried, not filtered out or
// ignored) whose boxes meet its move box, from one broadphase query of all the move boxes.
void Sweep::gather_candidates(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1) {
  size_t nm = movers.size();
  std::vector<btVector3> &mlo = sc.mlo, &mhi = sc.mhi;
  mlo.resize(nm);
  mhi.resize(nm);
  btVector3 lo(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT), hi = -lo;
  for (size_t i = 0; i < nm; ++i) {
    const Mover &m = movers[i];
    btTransform a = (robot && m.frame_link >= 0 ? lp0[m.frame_link] : base0) * m.rel;
    btTransform b = (robot && m.frame_link >= 0 ? lp1[m.frame_link] : base1) * m.rel;
    move_box(m, a, b, mlo[i], mhi[i]);
    if (m.bounded) {
      mlo[i].setMax(m.bound_lo);
      mhi[i].setMin(m.bound_hi);
    }
    lo.setMin(mlo[i]);
    hi.setMax(mhi[i]);
  }
  // the bodies in the union of the move boxes, their boxes side by side for the tests below
  struct Found : btBroadphaseAabbCallback {
    const Sweep *s;
    std::vector<const btCollisionObject *> &out;
    std::vector<btVector3> &lo, &hi;
    std::vector<std::array<int, 4>> &id;  // object, link, filter group, filter mask
    Found(Scratch &sc) : out(sc.found), lo(sc.found_lo), hi(sc.found_hi), id(sc.found_id) {
      out.clear();
      lo.clear();
      hi.clear();
      id.clear();
    }
    bool process(const btBroadphaseProxy *bp) override {
      auto *co = static_cast<const btCollisionObject *>(bp->m_clientObject);
      int ob, lb;
      decode_rb(co, ob, lb);
      if ((s->robot && ob == s->robot->id) || s->moving(ob) || s->ignored_by_all(ob, lb))
        return true;
      out.push_back(co);
      lo.push_back(bp->m_aabbMin);
      hi.push_back(bp->m_aabbMax);
      id.push_back({ob, lb, bp->m_collisionFilterGroup, bp->m_collisionFilterMask});
      return true;
    }
  } found(sc);
  found.s = this;
  w.dw->getBroadphase()->aabbTest(lo, hi, found);
  size_t nf = found.out.size();
  cand.clear();
  // the boxes by coordinate, so that one move box is tested against all of them in a loop
  // without branches (the test of TestAabbAgainstAabb2: boxes that touch meet)
  for (int k = 0; k < 6; ++k) sc.fb[k].resize(nf);
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      sc.fb[k][f] = found.lo[f][k];
      sc.fb[3 + k][f] = found.hi[f][k];
    }
  const double *flx = sc.fb[0].data(), *fly = sc.fb[1].data(), *flz = sc.fb[2].data(),
               *fhx = sc.fb[3].data(), *fhy = sc.fb[4].data(), *fhz = sc.fb[5].data();
  std::vector<int> &meets = sc.meets;
  meets.resize(nf + 1);
  for (size_t i = 0; i < nm; ++i) {
    Mover &m = movers[i];
    m.c0 = (int)cand.size();
    const btBroadphaseProxy *mine = m.co->getBroadphaseHandle();
    int group = mine ? mine->m_collisionFilterGroup : 1, mask = mine ? mine->m_collisionFilterMask : -1;
    const double mlx = mlo[i].x(), mly = mlo[i].y(), mlz = mlo[i].z();
    const double mhx = mhi[i].x(), mhy = mhi[i].y(), mhz = mhi[i].z();
    // the ignore records that may leave out pairs of this mover: their hit object and link
    std::vector<std::array<int, 2>> &mine_ignored = sc.mine_ignored;
    mine_ignored.clear();
    for (int r = 0; r < n_ignore; ++r) {
      const int *x = ignore4 + 4 * r;
      if ((x[0] == -1 || x[0] == m.obj) && (x[1] == -1 || x[1] == m.link)) mine_ignored.push_back({x[2], x[3]});
    }
    bool world_ignores = !w.ignored.empty();
    int *out = meets.data();
    size_t k = 0;
    for (size_t f = 0; f < nf; ++f) {
      out[k] = (int)f;
      k += !(mlx > fhx[f]) & !(mhx < flx[f]) & !(mly > fhy[f]) & !(mhy < fly[f]) &
           !(mlz > fhz[f]) & !(mhz < flz[f]);
    }
    for (size_t q = 0; q < k; ++q) {
      size_t f = out[q];
      const std::array<int, 4> &id = found.id[f];
      if (!(id[2] & mask) || !(group & id[3])) continue;
      if (world_ignores && w.pair_ignored(m.obj, m.link, id[0], id[1])) continue;
      bool left_out = false;
      for (const auto &x : mine_ignored) left_out |= (x[0] == -1 || x[0] == id[0]) && (x[1] == -1 || x[1] == id[1]);
      if (left_out) continue;
      cand.emplace_back();
      Cand &x = cand.back();
      for (int k = 0; k < 3; ++k) {
        x.lo[k] = found.lo[f][k];
        x.hi[k] = found.hi[f][k];
      }
      x.clear_until = 0;
      x.dist_k = -1;
      x.found = (int)f;
      x.done = 0;
    }
    m.nc = (int)cand.size() - m.c0;
  }
}

bool Sweep::hull_touches(const Mover &m, const btTransform &ta, const btTransform &tb, double grow,
                         const btCollisionObject *other) {
  const btBroadphaseProxy *h = other->getBroadphaseHandle();
  for (const Piece &p : m.pieces) {
    hull.set(p.shape, p.placed(ta), p.placed(tb), grow);
    btVector3 lo, hi;
    hull.getAabb(btTransform::getIdentity(), lo, hi);
    if (!TestAabbAgainstAabb2(lo, hi, h->m_aabbMin, h->m_aabbMax)) continue;
    if (may_touch(&hull, lo, hi, other)) return true;
  }
  return false;
}

// Bullet's contact query of M at pose T with OTHER, up to MAXD. A mover of one convex piece asks
// it with the piece (which the compound holds): the same contacts, for less work.
Closest Sweep::distance(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other) {
  if (m.pieces.e - m.pieces.b == 1) {
    probe.setCollisionShape(const_cast<btConvexShape *>(m.pieces.b->shape));
    probe.setWorldTransform(m.pieces.b->placed(t));
  } else {
    probe.setCollisionShape(const_cast<btCollisionShape *>(m.co->getCollisionShape()));
    probe.setWorldTransform(t);
  }
  Closest c(maxd);
  w.dw->contactPairTest(&probe, const_cast<btCollisionObject *>(other), c);
  return c;
}

// The distance of M at pose T from OTHER, searched up to MAXD (MAXD when farther), from GJK on
// its pieces; <= 0 when they touch.
double Sweep::distance_at(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other) {
  return pieces_distance(m.pieces, t, other, maxd);
}

// Whether M at pose T touches OTHER by Bullet's contact query (the discrete checks' verdict),
// asked where GJK finds them touching: true with the contact's POINT; false with the query's
// distance in D (MAXD when it finds nothing within MAXD). The two disagree by up to a tenth of
// a millimetre on grazing contacts with cylinders.
bool Sweep::touches(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other,
                    double &d, btVector3 &point) {
  Closest c = distance(m, t, maxd, other);
  if (c.found && c.best <= 0) {
    point = c.point;
    return true;
  }
  d = c.found ? c.best : maxd;
  return false;
}

// Earliest time in [ta, tb] at which M touches OTHER, or -1; POINT: where. DA and DB are the
// distances at the ends, NaN while unknown (computed here and handed on). The distance changes
// no faster than the mover's points move, so an interval is clear when DA + DB exceeds its path
// bound (going down to 0 and back up again needs at least that much motion), or when its hull
// misses OTHER (asked only when the distances leave it open). Halving, the earliest point of the
// halving grid where the distance is <= 0 is found; a touch is confirmed by the contact query
// only where it is the answer.
double Sweep::confirm(const Mover &m, const btCollisionObject *other, double ta, const btTransform &pa,
                      double &da, double tb, const btTransform &pb, double &db, int depth, btVector3 &point) {
  double h = tb - ta;
  double path = h * m.B, reach = h * m.Bp;  // the grid's path bound; how far a point can move
  if (std::isnan(da)) da = distance_at(m, pa, path + tol, other);
  if (da <= 0 && touches(m, pa, path + tol, other, da, point)) return ta;
  if (da > reach) return -1;
  bool leaf = path <= tol || depth > 40;
  if (std::isnan(db)) {
    db = distance_at(m, pb, path + tol, other);
    if (depth == 0 && db > 0 && kept) {  // the next sub-step starts there
      kept->dist = db;
      kept->dist_max = path + tol;
      kept->dist_k = kept_k;
    }
  }
  if (db > 0) {
    if (leaf || da + db > reach) return -1;
    if (!hull_touches(m, pa, pb, h * h * m.A / 8, other)) return -1;
  } else if (leaf) {
    return touches(m, pb, tol, other, db, point) ? tb : -1;
  }
  double tm = 0.5 * (ta + tb), dm = NAN;
  btTransform pm = pose_at(m, tm);
  double r = confirm(m, other, ta, pa, da, tm, pm, dm, depth + 1, point);
  return r >= 0 ? r : confirm(m, other, tm, pm, dm, tb, pb, db, depth + 1, point);
}

// The slot of time k / n: the base and the movers' anchors there (computed once); the movers'
// poses and boxes follow when asked for (slot_entry).
int Sweep::slot(int k) {
  if (point_slot[k] >= 0) return point_slot[k];
  size_t nm = movers.size();
  int sl = n_slots++;
  point_slot[k] = sl;
  slot_pose.resize((sl + 1) * nm);
  slot_lo.resize((sl + 1) * nm);
  slot_hi.resize((sl + 1) * nm);
  slot_have.resize((sl + 1) * nm);
  std::fill(slot_have.begin() + sl * nm, slot_have.end(), 0);
  slot_at.resize(sl + 1);
  slot_at[sl] = at_time((double)k / n);
  return sl;
}

// The candidates of FROM that the interval's box meets (the end boxes of slots a and b grown
// by GROW, within the start box grown by PATH), into KEEP; false when there is none.
bool Sweep::gather_interval(size_t a, size_t b, double tb, double grow, double path,
                            const std::vector<int> &from, std::vector<int> &keep) {
  btVector3 lo = slot_lo[a], hi = slot_hi[a];
  lo.setMin(slot_lo[b]);
  hi.setMax(slot_hi[b]);
  lo -= btVector3(grow, grow, grow);
  hi += btVector3(grow, grow, grow);
  lo.setMax(slot_lo[a] - btVector3(path, path, path));
  hi.setMin(slot_hi[a] + btVector3(path, path, path));
  keep.clear();
  for (int c : from) {
    const Cand &x = cand[c];
    if (x.done || tb <= x.clear_until) continue;
    if (x.meets(lo, hi)) keep.push_back(c);
  }
  return !keep.empty();
}

// The candidates of KEEP that mover m's hull between slots a and b (grown by GROW) clears are
// clear up to tb and leave KEEP; false when none is left.
bool Sweep::clear_by_hull(const Mover &m, size_t a, size_t b, double ta, double tb, double grow,
                          std::vector<int> &keep) {
  keep.erase(std::remove_if(keep.begin(), keep.end(),
                            [&](int c) {
                              if (ta < cand[c].clear_until ||
                                  hull_touches(m, slot_pose[a], slot_pose[b], grow, sc.found[cand[c].found]))
                                return false;
                              cand[c].clear_until = tb;
                              return true;
                            }),
             keep.end());
  return !keep.empty();
}

// Mover I over the sub-steps ka .. kb against the candidates pool[depth]: those whose boxes
// meet the interval's box (the end boxes grown by the chord bound, within the start box
// grown by the path bound) go down to halves, and at single sub-steps to the checks.
void Sweep::descend(size_t i, int ka, int kb, int depth) {
  Mover &m = movers[i];
  size_t a = slot_entry(ka, i), b = slot_entry(kb, i);
  double h = (double)(kb - ka) / n, ta = (double)ka / n, tb = (double)kb / n;
  // the chord bound from the acceleration bound A, but at the start of the move from 3 W B (the
  // pairs met there are those the start's contacts are looked for among, as they always were)
  double grow = h * h * (ka == 0 ? 3 * m.W * m.B : m.A) / 8, path = h * (ka == 0 ? m.B : m.Bp);
  std::vector<int> &keep = pool[depth + 1];
  if (!gather_interval(a, b, tb, grow, path, pool[depth], keep)) return;
  // one hull over eight sub-steps clears, in one test, a pair that passes close by (everything
  // before ta is clear already: the pair is clear up to tb); so do hulls over four and two,
  // where the hull over eight did not, but not at the start of the move, where the pairs met
  // are those the start's contacts are looked for among
  if ((kb - ka == 8 || (ka > 0 && (kb - ka == 4 || kb - ka == 2))) &&
      !clear_by_hull(m, a, b, ta, tb, grow, keep))
    return;
  if (kb - ka > 1) {
    int km = (ka + kb) / 2;
    descend(i, ka, km, depth + 1);
    descend(i, km, kb, depth + 1);
    return;
  }
  for (int c : keep) {
    Cand &x = cand[c];
    if (x.done || tb <= x.clear_until) continue;
    const btCollisionObject *other = sc.found[x.found];
    double known = NAN;
    // conservative advancement: no point of the mover moves faster than B, so a pair
    // apart by d at ta stays apart until ta + d / B
    if (ta >= x.clear_until) {
      double probe_d = std::max(tol, std::min(0.25, 4 * h * m.B));
      double d = x.kept_distance(ka, probe_d);
      if (std::isnan(d)) d = distance_at(m, slot_pose[a], probe_d, other);
      btVector3 point;
      bool touch = d <= 0 && touches(m, slot_pose[a], probe_d, other, d, point);
      if (ka == 0 && skip_start && d <= tol) {
        x.done = 1;
        continue;
      }
      if (touch) {  // touching at ta
        x.done = 1;
        report(m, other, ta, point);
        continue;
      }
      x.clear_until = ta + d / m.Bp;
      if (tb <= x.clear_until) continue;
      known = d;
    } else {
      known = x.kept_distance(ka, h * m.B + tol);
    }
    double db = NAN;
    btVector3 point;
    kept = &x;
    kept_k = kb;
    double t = confirm(m, other, ta, slot_pose[a], known, tb, slot_pose[b], db, 0, point);
    kept = nullptr;
    if (t < 0) continue;
    x.done = 1;
    report(m, other, t, point);
  }
}

void Sweep::report(const Mover &m, const btCollisionObject *other, double t, const btVector3 &point) {
  int ob, lb;
  decode_rb(other, ob, lb);
  hits.push_back({m.obj, m.link, ob, lb, t, point});
}

}  // namespace sweep
}  // namespace cn

// The sweep checks' reference search (flag CN_SWEEP_REFERENCE): the plain form of the search in
// cn_sweep_steps.cpp, for tests to hold the fast one against. It gives the same records, the
// work done plainly: every sub-step point's poses and boxes when the point is first reached,
// the swept hull tested before any distance, Bullet's contact query asked wherever GJK finds a
// touch (its distance then taken), no distance kept from one sub-step to the next, the links'
// forward kinematics computed for every pose asked.
#include "cn_sweep_impl.hpp"

namespace cn {
namespace sweep {

// The distance of M at pose T from OTHER up to MAXD: GJK's, or where that finds a touch, the
// contact query's (with its POINT), MAXD when the query finds nothing.
double Sweep::distance_reference(const Mover &m, const btTransform &t, double maxd,
                                 const btCollisionObject *other, btVector3 *point) {
  double d = distance_at(m, t, maxd, other);
  if (d > 0) return d;
  Closest c = distance(m, t, maxd, other);
  if (point) *point = c.point;
  return c.found ? c.best : maxd;
}

double Sweep::confirm_reference(const Mover &m, const btCollisionObject *other, double ta,
                                const btTransform &pa, double &da, double tb, const btTransform &pb,
                                double &db, btVector3 &point, int depth) {
  double h = tb - ta;
  double path = h * m.B;
  if (!hull_touches(m, pa, pb, 3 * h * h * m.W * m.B / 8, other)) return -1;
  if (std::isnan(da))
    da = distance_reference(m, pa, path + tol, other, &point);
  else if (da <= 0)  // found by the interval before, which did not ask for the point
    distance_reference(m, pa, path + tol, other, &point);
  if (da <= 0) return ta;
  if (da > path) return -1;
  if (std::isnan(db)) db = distance_reference(m, pb, path + tol, other);
  if (db > 0 && da + db > path) return -1;
  if (path <= tol || depth > 40) {
    if (db > 0) return -1;
    distance_reference(m, pb, tol, other, &point);
    return tb;
  }
  double tm = 0.5 * (ta + tb), dm = NAN;
  btTransform base = base_at(tm), pm;
  if (m.anchor < 0) {
    pm = base * m.rel_anchor;
  } else {
    fk(tm, base);
    pm = lp[m.anchor] * m.rel_anchor;
  }
  double r = confirm_reference(m, other, ta, pa, da, tm, pm, dm, point, depth + 1);
  return r >= 0 ? r : confirm_reference(m, other, tm, pm, dm, tb, pb, db, point, depth + 1);
}

// Every mover's pose and box at sub-step point K.
void Sweep::slot_reference(int k) {
  size_t nm = movers.size();
  for (size_t i = 0; i < nm; ++i) slot_entry(k, i);
}

void Sweep::descend_reference(size_t i, int ka, int kb, int depth) {
  Mover &m = movers[i];
  slot_reference(ka);
  slot_reference(kb);
  size_t a = slot_entry(ka, i), b = slot_entry(kb, i);
  double h = (double)(kb - ka) / n, ta = (double)ka / n, tb = (double)kb / n;
  double grow = 3 * h * h * m.W * m.B / 8, path = h * m.B;
  std::vector<int> &keep = pool[depth + 1];
  if (!gather_interval(a, b, tb, grow, path, pool[depth], keep)) return;
  if (kb - ka == 8 && !clear_by_hull(m, a, b, ta, tb, grow, keep)) return;
  if (kb - ka > 1) {
    int km = (ka + kb) / 2;
    descend_reference(i, ka, km, depth + 1);
    descend_reference(i, km, kb, depth + 1);
    return;
  }
  for (int c : keep) {
    Cand &x = cand[c];
    if (x.done || tb <= x.clear_until) continue;
    const btCollisionObject *other = sc.found[x.found];
    double known = NAN;
    if (ta >= x.clear_until) {
      double probe_d = std::max(tol, std::min(0.25, 4 * h * m.B));
      btVector3 at_point;
      double d = distance_reference(m, slot_pose[a], probe_d, other, &at_point);
      if (ka == 0 && skip_start && d <= tol) {
        x.done = 1;
        continue;
      }
      if (d <= 0) {
        x.done = 1;
        report(m, other, ta, at_point);
        continue;
      }
      x.clear_until = ta + d / m.B;
      if (tb <= x.clear_until) continue;
      known = d;
    }
    btVector3 point(0, 0, 0);
    double db = NAN;
    double t = confirm_reference(m, other, ta, slot_pose[a], known, tb, slot_pose[b], db, point, 0);
    if (t < 0) continue;
    x.done = 1;
    report(m, other, t, point);
  }
}

}  // namespace sweep
}  // namespace cn

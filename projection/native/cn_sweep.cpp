// Sweep checks: what a robot (its links and rigidly attached objects) or a body passes through
// on its way between two poses, not only what it touches at them.
//
// The move is cut into sub-steps of at most `max_step` summed rotation (rad) and translation
// (m). In a sub-step every moving piece covers the convex hull of its two end placements grown
// by a bound on how far its real path strays from the straight chords between them: with W the
// summed rotation and B a bound on the path length of any of its points in the sub-step, the
// path stays within 3*W*B/8 of the chords (its acceleration is at most 3*W*B). A hull that
// touches another object is confirmed by halving the interval on distances: an interval whose
// pieces cannot reach the object (distance at its start beyond its path bound) is clear, one
// whose start is at or below distance 0 is the first contact. A pair is reported only where a
// computed distance is <= 0, and missed only when it never penetrates deeper than `tolerance`.
// The sub-steps (a power of two) are visited from the whole move down by halving, each mover's
// box over an interval sorting out the candidates it can meet there; a pair found apart by d is
// not looked at again before the move could have closed d (conservative advancement).
#include "cn_sweep.hpp"

namespace cn {
namespace {
using namespace sweep;

// The convex pieces of shape S placed at LOCAL, into OUT; a triangle mesh or plane stands in
// as its local box (kept in OWNED).
void collect_pieces(const btCollisionShape *s, const btTransform &local, std::vector<Piece> &out,
                    std::vector<std::unique_ptr<btCollisionShape>> &owned) {
  if (s->isCompound()) {
    auto *c = static_cast<const btCompoundShape *>(s);
    for (int i = 0; i < c->getNumChildShapes(); ++i)
      collect_pieces(c->getChildShape(i), local * c->getChildTransform(i), out, owned);
  } else if (s->isConvex()) {
    out.push_back({static_cast<const btConvexShape *>(s), local});
  } else {
    btVector3 lo, hi;
    s->getAabb(btTransform::getIdentity(), lo, hi);
    btVector3 half = (hi - lo) * 0.5;
    half.setMax(btVector3(1e-4, 1e-4, 1e-4));
    auto box = std::make_unique<btBoxShape>(half);
    box->setMargin(0);
    btTransform at(btQuaternion::getIdentity(), (hi + lo) * 0.5);
    out.push_back({box.get(), local * at});
    owned.push_back(std::move(box));
  }
}

// ROBOT's links as the sweeps need them (chains, pieces, radii), made once per model and
// remade when a link body's shape is not the one they were made for.
std::shared_ptr<const ModelSweepInfo> model_sweep_info(const Object &robot) {
  const Model &md = *robot.model;
  std::lock_guard<std::mutex> lock(md.cache_mu);
  auto info = std::static_pointer_cast<const ModelSweepInfo>(md.sweep_links);
  bool ok = info && info->links.size() == robot.link_rb.size();
  for (size_t l = 0; ok && l < robot.link_rb.size(); ++l)
    ok = (robot.link_rb[l] ? robot.link_rb[l]->getCollisionShape() : nullptr) == info->links[l].shape;
  if (ok) return info;
  auto fresh = std::make_shared<ModelSweepInfo>();
  fresh->links.resize(robot.link_rb.size());
  for (size_t l = 0; l < robot.link_rb.size(); ++l) {
    if (!robot.link_rb[l]) continue;
    LinkInfo &li = fresh->links[l];
    li.shape = robot.link_rb[l]->getCollisionShape();
    link_chain(md, (int)l, li.chain);
    collect_pieces(li.shape, btTransform::getIdentity(), li.pieces, fresh->owned);
    li.radius = shape_radius(li.shape);
  }
  md.sweep_links = fresh;
  return fresh;
}

Scratch &scratch() {
  static thread_local Scratch s;
  return s;
}

struct Sweep {
  World &w;
  Scratch &sc = scratch();
  const Object *robot = nullptr;            // null for a body sweep
  btTransform base0, base1;
  btQuaternion rot0, rot1;
  double angle = 0;                          // base rotation over the move
  std::vector<double> q0, q1, qt, dv;        // dv: joint value changes (mimic applied)
  std::vector<char> &needed = sc.needed;
  std::vector<btTransform> &lp = sc.lp;      // link poses at the time asked last
  std::vector<Mover> movers;
  std::shared_ptr<const ModelSweepInfo> info;            // the robot's links (model_sweep_info)
  std::vector<std::unique_ptr<std::vector<Piece>>> body_pieces;  // pieces of moving bodies
  std::vector<std::unique_ptr<std::vector<int>>> body_chains;    // chains of attached bodies
  // the movers' candidates, side by side (Mover::c0, nc): the bodies, their broadphase boxes,
  // whether a pair is done (reported, or left out as a start contact) and the time before
  // which it cannot be reached
  std::vector<Cand> &cand = sc.cand;
  std::vector<std::unique_ptr<btCollisionShape>> owned;  // boxes standing in for concave pieces
  std::vector<int> moving_ids;                           // the robot and what it carries
  bool any_anchor = false;                               // some mover hangs from a moving joint

  bool moving(int id) const {
    return std::find(moving_ids.begin(), moving_ids.end(), id) != moving_ids.end();
  }
  const int *ignore4 = nullptr;
  int n_ignore = 0;
  double tol = 1e-3;
  bool skip_start = false;
  btCollisionObject probe;
  SweptHull hull;
  std::vector<Hit> hits;

  Sweep(World &wd, const int *ign, int n_ign, double tolerance, int flags)
      : w(wd), ignore4(ign), n_ignore(n_ign), tol(tolerance),
        skip_start((flags & CN_SWEEP_SKIP_START_CONTACTS) != 0) {}

  // The base (or body) poses at the ends, then the joint changes (q0, q1 set before).
  void set_ends(const btTransform &a, const btTransform &b) {
    set_base(a, b);
    prepare();
  }

  void set_base(const btTransform &a, const btTransform &b) {
    base0 = a;
    base1 = b;
    rot0 = a.getRotation();
    rot1 = b.getRotation();
    if (rot0.dot(rot1) < 0) rot1 = -rot1;
    angle = rot0.angleShortestPath(rot1);
  }

  btTransform base_at(double t) const {
    btQuaternion r = angle > 1e-12 ? rot0.slerp(rot1, t) : rot0;
    return btTransform(r, base0.getOrigin().lerp(base1.getOrigin(), t));
  }

  // The frame of mover M at time T; the links the movers hang from (their anchors, see run)
  // computed into lp, unless FK_DONE says they are for T already.
  btTransform pose_at(const Mover &m, double t, bool fk_done = false) {
    btTransform base = base_at(t);
    if (m.anchor < 0) return base * m.rel_anchor;
    if (!fk_done) fk(t, base);
    return lp[m.anchor] * m.rel_anchor;
  }

  void fk(double t, const btTransform &base) {
    for (size_t j = 0; j < qt.size(); ++j) qt[j] = q0[j] + t * (q1[j] - q0[j]);
    compute_link_poses(*robot->model, base, qt, lp, &needed);
  }

  Mover &add_mover(int obj, int link, const btCollisionObject *co, int frame_link,
                   const btTransform &rel, const std::vector<int> *chain,
                   const std::vector<Piece> &pieces, double radius) {
    movers.emplace_back();
    Mover &m = movers.back();
    m.obj = obj;
    m.link = link;
    m.co = co;
    m.frame_link = frame_link;
    m.rel = rel;
    m.chain = chain;
    m.pieces = {pieces.data(), pieces.data() + pieces.size()};
    m.radius = radius;
    if (!moving(obj)) moving_ids.push_back(obj);
    return m;
  }

  // A moving body (attached object or a body swept on its own): its pieces kept here.
  void add_body_mover(int obj, const btCollisionObject *co, int frame_link, const btTransform &rel,
                      std::vector<int> chain) {
    body_chains.push_back(std::make_unique<std::vector<int>>(std::move(chain)));
    body_pieces.push_back(std::make_unique<std::vector<Piece>>());
    const btCollisionShape *s = co->getCollisionShape();
    collect_pieces(s, btTransform::getIdentity(), *body_pieces.back(), owned);
    add_mover(obj, -1, co, frame_link, rel, body_chains.back().get(), *body_pieces.back(),
              shape_radius(s));
  }

  // Rigidly attached bodies of PARENT (and theirs), hanging from FRAME_LINK at REL.
  void add_attached(int parent, int frame_link, const btTransform &rel, int depth) {
    if (depth > 16) return;
    for (const Attachment &a : w.attachments) {
      if (a.parent != parent || a.loose) continue;
      Object *c = w.objects[a.obj];
      if (!c || c->kind != CN_BODY || !c->rb || moving(a.obj)) continue;
      int fl = depth == 0 ? a.link : frame_link;
      btTransform r = depth == 0 ? a.rel : rel * a.rel;
      moving_ids.push_back(a.obj);  // carried objects are never hit by their carrier
      std::vector<int> chain;
      if (robot && fl >= 0) link_chain(*robot->model, fl, chain);
      if (chain_moves(chain)) add_body_mover(a.obj, c->rb, fl, r, std::move(chain));
      add_attached(a.obj, fl, r, depth + 1);
    }
  }

  // W and B of every mover over the whole move (see the file comment), from the chain of its
  // movable joints: the distance between consecutive joint origins is fixed for revolute joints
  // and convex in the value of a prismatic one, so its larger end value bounds it.
  void bound_movers(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1) {
    double dtrans = (base1.getOrigin() - base0.getOrigin()).length();
    // a robot turning on the spot about the vertical, its joints kept
    bool turn_in_place = robot && base0.getOrigin() == base1.getOrigin() && rot0.x() == 0 &&
                         rot0.y() == 0 && rot1.x() == 0 && rot1.y() == 0 && q0 == q1;
    for (Mover &m : movers) {
      btVector3 o0 = (robot && m.frame_link >= 0 ? lp0[m.frame_link] : base0) * m.rel.getOrigin();
      btVector3 o1 = (robot && m.frame_link >= 0 ? lp1[m.frame_link] : base1) * m.rel.getOrigin();
      // points from the mover's origin back to the base: reach[k] bounds the distance from
      // joint chain[k]'s origin to any point of the mover
      double reach = m.radius;
      double W = angle, B = dtrans;
      btVector3 p0 = o0, p1 = o1;
      int k0 = first_changing(*m.chain);
      m.bounded = false;
      for (int k = (int)m.chain->size() - 1; k >= 0; --k) {
        int j = (*m.chain)[k];
        int child = robot->model->joints[j].child;
        btVector3 c0 = lp0[child].getOrigin(), c1 = lp1[child].getOrigin();
        reach += std::max((p0 - c0).length(), (p1 - c1).length());
        p0 = c0;
        p1 = c1;
        if (k == k0) {  // this joint's origin stays put: the mover stays within reach of it
          double r = reach + 1e-6;   // and a margin for the rounding of the poses along the way
          m.bounded = true;
          m.bound_lo = c0 - btVector3(r, r, r);
          m.bound_hi = c0 + btVector3(r, r, r);
        }
        double d = std::fabs(dv[j]);
        if (robot->model->joints[j].type == CN_JOINT_PRISMATIC) {
          B += d;
        } else {
          W += d;
          B += d * reach;
        }
      }
      reach += std::max((p0 - base0.getOrigin()).length(), (p1 - base1.getOrigin()).length());
      B += angle * reach;
      if (turn_in_place) {  // the mover's origin circles the base's vertical axis at its height
        const btVector3 &b = base0.getOrigin();
        double rho = std::sqrt((o0.x() - b.x()) * (o0.x() - b.x()) + (o0.y() - b.y()) * (o0.y() - b.y()));
        double h = rho + m.radius + 1e-6, v = m.radius + 1e-6;
        m.bounded = true;
        m.bound_lo = btVector3(b.x() - h, b.y() - h, o0.z() - v);
        m.bound_hi = btVector3(b.x() + h, b.y() + h, o0.z() + v);
      }
      m.W = W;
      m.B = B;
    }
  }

  // The first joint on CHAIN whose value changes in this move (its own value or the one it
  // mimics differs between the ends), when the base stays and that joint is revolute: its origin
  // does not move. -1 otherwise.
  int first_changing(const std::vector<int> &chain) const {
    if (!robot || base_moves) return -1;
    const Model &md = *robot->model;
    for (size_t k = 0; k < chain.size(); ++k) {
      const JointM &jm = md.joints[chain[k]];
      int src = jm.mimic >= 0 ? jm.mimic : chain[k];
      if (q0[src] == q1[src]) continue;
      return jm.type == CN_JOINT_REVOLUTE || jm.type == CN_JOINT_CONTINUOUS ? (int)k : -1;
    }
    return -1;
  }

  // Whether an ignore pair leaves out every mover's contacts with link HLINK of HOBJ.
  bool ignored_by_all(int hobj, int hlink) const {
    for (int i = 0; i < n_ignore; ++i) {
      const int *r = ignore4 + 4 * i;
      if (r[0] == -1 && r[1] == -1 && (r[2] == -1 || r[2] == hobj) && (r[3] == -1 || r[3] == hlink))
        return true;
    }
    return false;
  }

  bool ignored(const Mover &m, int hobj, int hlink) const {
    if (w.pair_ignored(m.obj, m.link, hobj, hlink)) return true;
    for (int i = 0; i < n_ignore; ++i) {
      const int *r = ignore4 + 4 * i;
      if ((r[0] == -1 || r[0] == m.obj) && (r[1] == -1 || r[1] == m.link) &&
          (r[2] == -1 || r[2] == hobj) && (r[3] == -1 || r[3] == hlink))
        return true;
    }
    return false;
  }

  // The box mover M can reach anywhere on its way from T0 to T1: its box at the start grown by
  // its path bound, cut down to the box of its two end boxes grown by the chord bound.
  void move_box(const Mover &m, const btTransform &t0, const btTransform &t1, btVector3 &lo,
                btVector3 &hi) const {
    btVector3 lo0, hi0, lo1, hi1;
    m.co->getCollisionShape()->getAabb(t0, lo0, hi0);
    m.co->getCollisionShape()->getAabb(t1, lo1, hi1);
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
  void gather_candidates(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1) {
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
        if (ignored(m, id[0], id[1])) continue;
        cand.emplace_back();
        Cand &x = cand.back();
        for (int k = 0; k < 3; ++k) {
          x.lo[k] = found.lo[f][k];
          x.hi[k] = found.hi[f][k];
        }
        x.clear_until = 0;
        x.found = (int)f;
        x.done = 0;
      }
      m.nc = (int)cand.size() - m.c0;
    }
  }

  bool hull_touches(const Mover &m, const btTransform &ta, const btTransform &tb, double grow,
                    const btCollisionObject *other) {
    const btBroadphaseProxy *h = other->getBroadphaseHandle();
    for (const Piece &p : m.pieces) {
      hull.set(p.shape, ta * p.local, tb * p.local, grow);
      btVector3 lo, hi;
      hull.getAabb(btTransform::getIdentity(), lo, hi);
      if (!TestAabbAgainstAabb2(lo, hi, h->m_aabbMin, h->m_aabbMax)) continue;
      if (convex_distance(&hull, btTransform::getIdentity(), other, 1e-9) <= 0) return true;
    }
    return false;
  }

  Closest distance(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other) {
    probe.setCollisionShape(const_cast<btCollisionShape *>(m.co->getCollisionShape()));
    probe.setWorldTransform(t);
    Closest c(maxd);
    w.dw->contactPairTest(&probe, const_cast<btCollisionObject *>(other), c);
    return c;
  }

  // The distance of M at pose T from OTHER, searched up to MAXD (MAXD when farther): from GJK
  // on its pieces, and where that finds a touch, from Bullet's contact query, which also gives
  // the POINT of contact (the one the discrete checks use).
  double distance_at(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other,
                     btVector3 *point = nullptr) {
    double d = maxd;
    for (const Piece &p : m.pieces) {
      d = std::min(d, convex_distance(p.shape, t * p.local, other, d));
      if (d <= 0) break;
    }
    if (d > 0) return d;
    Closest c = distance(m, t, maxd, other);
    if (point) *point = c.point;
    return c.found ? c.best : maxd;
  }

  // Earliest time in [ta, tb] at which M touches OTHER (distance <= 0), or -1. DA and DB are
  // the distances at the ends, NaN while unknown (computed here and handed on). The distance
  // changes no faster than the mover's points move, so an interval is clear when its hull
  // misses OTHER, or when DA + DB exceeds its path bound (going down to 0 and back up again
  // needs at least that much motion).
  double confirm(const Mover &m, const btCollisionObject *other, double ta, const btTransform &pa,
                 double &da, double tb, const btTransform &pb, double &db, btVector3 &point,
                 int depth) {
    double h = tb - ta;
    double path = h * m.B;
    if (!hull_touches(m, pa, pb, 3 * h * h * m.W * m.B / 8, other)) return -1;
    if (std::isnan(da))
      da = distance_at(m, pa, path + tol, other, &point);
    else if (da <= 0)  // found by the interval before, which did not ask for the point
      distance_at(m, pa, path + tol, other, &point);
    if (da <= 0) return ta;
    if (da > path) return -1;
    if (std::isnan(db)) db = distance_at(m, pb, path + tol, other);
    if (db > 0 && da + db > path) return -1;
    if (path <= tol || depth > 40) {
      if (db > 0) return -1;
      distance_at(m, pb, tol, other, &point);
      return tb;
    }
    double tm = 0.5 * (ta + tb), dm = NAN;
    btTransform pm = pose_at(m, tm);
    double r = confirm(m, other, ta, pa, da, tm, pm, dm, point, depth + 1);
    return r >= 0 ? r : confirm(m, other, tm, pm, dm, tb, pb, db, point, depth + 1);
  }

  bool base_moves = false;

  // needed: the links LINK_OF(mover) gives and the links on their way from the root.
  template <class F>
  void mark_needed(F link_of) {
    const Model &md = *robot->model;
    needed.assign(md.links.size(), 0);
    for (const Mover &m : movers)
      for (int l = link_of(m); l >= 0;) {
        if (needed[l]) break;
        needed[l] = 1;
        int pj = md.links[l].parent_joint;
        l = pj >= 0 ? md.joints[pj].parent : -1;
      }
    needed[md.root] = 1;
  }

  // Each mover's anchor: the child link of the last joint on its chain that changes in this
  // move (-1: none, it rides on the base), and its frame relative to the anchor at the start,
  // which stays so (the joints after the anchor keep their values). Only the anchors' poses
  // are computed along the move.
  void set_anchors(const std::vector<btTransform> &lp0) {
    any_anchor = false;
    for (Mover &m : movers) {
      m.anchor = -1;
      if (!robot || m.frame_link < 0) {
        m.rel_anchor = m.rel;
        continue;
      }
      for (int j : *m.chain)
        if (dv[j] != 0) m.anchor = robot->model->joints[j].child;
      any_anchor |= m.anchor >= 0;
      m.rel_anchor = (m.anchor >= 0 ? lp0[m.anchor] : base0).inverseTimes(lp0[m.frame_link] * m.rel);
    }
  }

  // The joint changes, once the ends are set.
  void prepare() {
    base_moves = (base1.getOrigin() - base0.getOrigin()).length2() > 0 || angle > 0;
    if (!robot) return;
    const Model &md = *robot->model;
    dv.assign(q0.size(), 0);
    for (size_t j = 0; j < q0.size(); ++j)
      dv[j] = model_joint_value(md, q1, (int)j) - model_joint_value(md, q0, (int)j);
  }

  bool chain_moves(const std::vector<int> &chain) const {
    if (base_moves) return true;
    for (int j : chain)
      if (dv[j] != 0) return true;
    return false;
  }

  // The link poses (those NEEDED) for BASE and joint values Q, into OUT: the robot's own when
  // it stands so (the same computation made them), else computed.
  void end_link_poses(const btTransform &base, const std::vector<double> &q, std::vector<btTransform> &out) {
    if (base == robot->base && q == robot->q && robot->link_pose.size() == robot->model->links.size()) {
      out = robot->link_pose;
      return;
    }
    compute_link_poses(*robot->model, base, q, out, &needed);
  }

  void run(double max_step) {
    // the boxes of what the movers may meet; the robot's and the carried objects' own boxes
    // are not read (they are left out of the candidates)
    sync_aabbs_except(w, [&](int ob) { return (robot && ob == robot->id) || moving(ob); });
    std::vector<btTransform> &lp0 = sc.lp0, &lp1 = sc.lp1;
    if (robot) {  // the poses at the ends of the links the movers hang from
      mark_needed([](const Mover &m) { return m.frame_link; });
      end_link_poses(base0, q0, lp0);
      end_link_poses(base1, q1, lp1);
    }
    bound_movers(lp0, lp1);
    // movers that do not move meet nothing they did not touch already
    movers.erase(std::remove_if(movers.begin(), movers.end(),
                                [&](const Mover &m) { return !base_moves && m.B == 0; }),
                 movers.end());
    if (movers.empty()) return;
    set_anchors(lp0);
    double total_rot = angle, total_trans = (base1.getOrigin() - base0.getOrigin()).length();
    if (robot) {
      std::vector<char> seen(q0.size(), 0);
      for (const Mover &m : movers)
        for (int j : *m.chain)
          if (!seen[j]) {
            seen[j] = 1;
            (robot->model->joints[j].type == CN_JOINT_PRISMATIC ? total_trans : total_rot) += std::fabs(dv[j]);
          }
      mark_needed([](const Mover &m) { return m.anchor; });
      qt = q0;
      lp = lp0;
    }
    double n_real = std::ceil(std::max(total_rot, total_trans) / max_step);
    if (n_real > 1e5)
      fail(CN_E_ARG, "the move needs %.0f sub-steps of at most %s, more than 100000: raise the maximum step",
           n_real, num(max_step).c_str());
    levels = 0;
    while ((double)(1 << levels) < n_real) ++levels;
    n = 1 << levels;
    gather_candidates(lp0, lp1);
    point_slot.assign(n + 1, -1);
    size_t expect = (size_t)std::min(n + 1, 2 * levels + 8) * movers.size();
    slot_pose.reserve(expect);
    slot_lo.reserve(expect);
    slot_hi.reserve(expect);
    pool.resize(levels + 2);
    for (size_t i = 0; i < movers.size(); ++i) {
      if (movers[i].nc == 0) continue;
      std::vector<int> &all = pool[0];
      all.clear();
      for (int c = movers[i].c0; c < movers[i].c0 + movers[i].nc; ++c) all.push_back(c);
      descend(i, 0, n, 0);
    }
  }

  // ---- the time hierarchy: the move's n = 2^levels sub-steps, halved from the whole move
  int levels = 0, n = 1;
  std::vector<int> &point_slot = sc.point_slot;  // sub-step point k -> its slot (-1: none yet)
  int n_slots = 0;
  std::vector<btTransform> &slot_pose = sc.slot_pose;  // per slot, one pose per mover
  std::vector<btVector3> &slot_lo = sc.slot_lo, &slot_hi = sc.slot_hi;  // per slot, one box per mover
  std::vector<std::vector<int>> &pool = sc.pool;        // candidate lists per depth

  // The slot of the movers' poses and boxes at time k / n (computed once).
  int slot(int k) {
    if (point_slot[k] >= 0) return point_slot[k];
    size_t nm = movers.size();
    int sl = n_slots++;
    point_slot[k] = sl;
    slot_pose.resize((sl + 1) * nm);
    slot_lo.resize((sl + 1) * nm);
    slot_hi.resize((sl + 1) * nm);
    double t = (double)k / n;
    btTransform base = base_at(t);
    if (robot && any_anchor) fk(t, base);
    for (size_t i = 0; i < nm; ++i) {
      const Mover &m = movers[i];
      if (m.nc == 0) continue;
      size_t at = sl * nm + i;
      slot_pose[at] = m.anchor < 0 ? base * m.rel_anchor : lp[m.anchor] * m.rel_anchor;
      m.co->getCollisionShape()->getAabb(slot_pose[at], slot_lo[at], slot_hi[at]);
    }
    return sl;
  }

  // Mover I over the sub-steps ka .. kb against the candidates pool[depth]: those whose boxes
  // meet the interval's box (the end boxes grown by the chord bound, within the start box
  // grown by the path bound) go down to halves, and at single sub-steps to the checks.
  void descend(size_t i, int ka, int kb, int depth) {
    Mover &m = movers[i];
    size_t nm = movers.size();
    size_t a = slot(ka) * nm + i, b = slot(kb) * nm + i;
    double h = (double)(kb - ka) / n, ta = (double)ka / n, tb = (double)kb / n;
    double grow = 3 * h * h * m.W * m.B / 8, path = h * m.B;
    btVector3 lo = slot_lo[a], hi = slot_hi[a];
    lo.setMin(slot_lo[b]);
    hi.setMax(slot_hi[b]);
    lo -= btVector3(grow, grow, grow);
    hi += btVector3(grow, grow, grow);
    lo.setMax(slot_lo[a] - btVector3(path, path, path));
    hi.setMin(slot_hi[a] + btVector3(path, path, path));
    std::vector<int> &keep = pool[depth + 1];
    keep.clear();
    for (int c : pool[depth]) {
      const Cand &x = cand[c];
      if (x.done || tb <= x.clear_until) continue;
      if (x.meets(lo, hi)) keep.push_back(c);
    }
    if (keep.empty()) return;
    if (kb - ka == 8) {
      // one hull over eight sub-steps clears, in one test, a pair that passes close by
      // (everything before ta is clear already: the pair is clear up to tb)
      keep.erase(std::remove_if(keep.begin(), keep.end(),
                                [&](int c) {
                                  if (ta < cand[c].clear_until ||
                                      hull_touches(m, slot_pose[a], slot_pose[b], grow, sc.found[cand[c].found]))
                                    return false;
                                  cand[c].clear_until = tb;
                                  return true;
                                }),
                 keep.end());
      if (keep.empty()) return;
    }
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
        btVector3 at_point;
        double d = distance_at(m, slot_pose[a], probe_d, other, &at_point);
        if (ka == 0 && skip_start && d <= tol) {
          x.done = 1;
          continue;
        }
        if (d <= 0) {  // touching at ta
          x.done = 1;
          int ob, lb;
          decode_rb(other, ob, lb);
          hits.push_back({m.obj, m.link, ob, lb, ta, at_point});
          continue;
        }
        x.clear_until = ta + d / m.B;
        if (tb <= x.clear_until) continue;
        known = d;
      }
      btVector3 point(0, 0, 0);
      double db = NAN;
      double t = confirm(m, other, ta, slot_pose[a], known, tb, slot_pose[b], db, point, 0);
      if (t < 0) continue;
      x.done = 1;
      int ob, lb;
      decode_rb(other, ob, lb);
      hits.push_back({m.obj, m.link, ob, lb, t, point});
    }
  }
};

void check_ignore(World &w, const int *ignore4, int n) {
  if (n < 0) fail(CN_E_ARG, "ignore list of %d pairs, expected >= 0", n);
  if (n > 0) check_ptr(ignore4, "ignore list");
  for (int i = 0; i < n; ++i) {
    const int *r = ignore4 + 4 * i;
    for (int s = 0; s < 2; ++s) {
      int o = r[2 * s], l = r[2 * s + 1];
      if (o == -1) {
        if (l != -1) fail(CN_E_ARG, "ignore pair %d: link %d of any object (-1), expected link -1", i, l);
        continue;
      }
      Object &obj = w.obj(o, s == 0 ? "ignore pair's moving object" : "ignore pair's hit object");
      int nl = obj.kind == CN_BODY ? 0 : (int)obj.link_rb.size();
      if (l < -1 || l >= nl)
        fail(CN_E_HANDLE, "ignore pair %d: link %d out of range -1..%d of object %d", i, l, nl - 1, o);
    }
  }
}

void check_common(World &w, const int *ignore4, int n_ignore, double max_step, double tol,
                  int flags, int cap, const void *o4, const void *od) {
  check_ignore(w, ignore4, n_ignore);
  check_positive(max_step, "maximum step");
  check_positive(tol, "tolerance");
  if (flags & ~CN_SWEEP_SKIP_START_CONTACTS) fail(CN_E_ARG, "sweep flags %d, expected 0 or %d", flags, CN_SWEEP_SKIP_START_CONTACTS);
  if (cap < 0) fail(CN_E_ARG, "capacity %d, expected >= 0", cap);
  if (cap > 0) {
    check_ptr(o4, "contact output");
    check_ptr(od, "fraction and point output");
  }
}

int write_hits(std::vector<Hit> &hits, int *out4, double *outd, int cap) {
  std::sort(hits.begin(), hits.end());
  int n = (int)hits.size();
  for (int i = 0; i < n && i < cap; ++i) {
    const Hit &h = hits[i];
    out4[4 * i] = h.obj;
    out4[4 * i + 1] = h.link;
    out4[4 * i + 2] = h.hobj;
    out4[4 * i + 3] = h.hlink;
    outd[4 * i] = h.t;
    for (int k = 0; k < 3; ++k) outd[4 * i + 1 + k] = h.point[k];
  }
  return n;
}

}  // namespace
}  // namespace cn

using namespace cn;

extern "C" {

int cn_robot_sweep_check(int wh, int rh, const double *base_from7, const double *q_from,
                         const double *base_to7, const double *q_to, int nq, const int *ignore4,
                         int n_ignore, double max_step, double tolerance, int flags, int *out4,
                         double *outd, int cap) {
  return guard([&] {
    World &w = world(wh);
    Object &r = w.robot(rh);
    btTransform b0 = read_pose(base_from7, "start base pose"), b1 = read_pose(base_to7, "end base pose");
    int nj = (int)r.model->joints.size();
    if (nq != nj) fail(CN_E_ARG, "joint vectors of %d values, expected %d (every joint of object %d)", nq, nj, rh);
    check_ptr(q_from, "start joint values");
    check_ptr(q_to, "end joint values");
    for (int j = 0; j < nj; ++j) {
      if (!std::isfinite(q_from[j])) fail(CN_E_ARG, "start joint value %d is %s", j, num(q_from[j]).c_str());
      if (!std::isfinite(q_to[j])) fail(CN_E_ARG, "end joint value %d is %s", j, num(q_to[j]).c_str());
    }
    check_common(w, ignore4, n_ignore, max_step, tolerance, flags, cap, out4, outd);
    std::unique_ptr<Sweep> s(new Sweep(w, ignore4, n_ignore, tolerance, flags));
    s->robot = &r;
    s->q0.assign(q_from, q_from + nj);
    s->q1.assign(q_to, q_to + nj);
    s->set_ends(b0, b1);
    s->info = model_sweep_info(r);
    s->movers.reserve(r.link_rb.size() + w.attachments.size());
    for (size_t l = 0; l < r.link_rb.size(); ++l) {
      if (!r.link_rb[l]) continue;
      const LinkInfo &li = s->info->links[l];
      if (s->chain_moves(li.chain))
        s->add_mover(rh, (int)l, r.link_rb[l], (int)l, btTransform::getIdentity(), &li.chain,
                     li.pieces, li.radius);
    }
    s->add_attached(rh, -1, btTransform::getIdentity(), 0);
    s->run(max_step);
    return write_hits(s->hits, out4, outd, cap);
  });
}

int cn_body_sweep_check(int wh, int bh, const double *from7, const double *to7, const int *ignore4,
                        int n_ignore, double max_step, double tolerance, int flags, int *out4,
                        double *outd, int cap) {
  return guard([&] {
    World &w = world(wh);
    Object &b = w.body(bh);
    btTransform t0 = read_pose(from7, "start pose"), t1 = read_pose(to7, "end pose");
    if (b.shape && b.shape->kind == 0) fail(CN_E_ARG, "body %d is a plane: it cannot sweep", bh);
    check_common(w, ignore4, n_ignore, max_step, tolerance, flags, cap, out4, outd);
    std::unique_ptr<Sweep> s(new Sweep(w, ignore4, n_ignore, tolerance, flags));
    s->set_ends(t0, t1);
    s->movers.reserve(1 + w.attachments.size());
    s->add_body_mover(bh, b.rb, -1, btTransform::getIdentity(), {});
    s->add_attached(bh, -1, btTransform::getIdentity(), 1);
    s->run(max_step);
    return write_hits(s->hits, out4, outd, cap);
  });
}

}  // extern "C"

// Sweep checks: what a robot (its links and rigidly attached objects) or a body passes through
// on its way between two poses, not only what it touches at them. This file: the C entry points,
// the sweep's setup (the ends, the movers and their bounds) and its run; the search over the
// sub-steps is in cn_sweep_steps.cpp, struct Sweep in cn_sweep_impl.hpp.
//
// The move is cut into sub-steps of at most `max_step` summed rotation (rad) and translation
// (m). In a sub-step every moving piece covers the convex hull of its two end placements grown
// by a bound on how far its real path strays from the straight chords between them: with W the
// summed rotation and B a bound on the path length of any of its points in the sub-step, the
// path stays within 3*W*B/8 of the chords (its acceleration is at most 3*W*B). Each mover's W
// and B over the whole move come from bound_movers here; the hulls and distances that use them
// are cn_sweep_steps.cpp's.
#include "cn_sweep_impl.hpp"

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
    out.push_back({static_cast<const btConvexShape *>(s), local, local == btTransform::getIdentity()});
  } else {
    btVector3 lo, hi;
    s->getAabb(btTransform::getIdentity(), lo, hi);
    btVector3 half = (hi - lo) * 0.5;
    half.setMax(btVector3(1e-4, 1e-4, 1e-4));
    auto box = std::make_unique<btBoxShape>(half);
    box->setMargin(0);
    btTransform at(btQuaternion::getIdentity(), (hi + lo) * 0.5);
    out.push_back({box.get(), local * at, false});
    owned.push_back(std::move(box));
  }
}

// ROBOT's links as the sweeps need them (chains, pieces, radii), made once per model and
// remade when a link body's shape is not the one they were made for; kept with ROBOT once
// checked (its link bodies keep their shapes).
// btCompoundShape's local box, read through a pointer to its member taken where it may be named
struct CompoundBoxAccess : btCompoundShape {
  static btVector3 btCompoundShape::*lo() { return &CompoundBoxAccess::m_localAabbMin; }
  static btVector3 btCompoundShape::*hi() { return &CompoundBoxAccess::m_localAabbMax; }
};

}  // namespace

void sweep::CompoundBox::take(const btCompoundShape *c) {
  // the steps of btCompoundShape::getAabb before the transform
  const btVector3 &lmin = c->*CompoundBoxAccess::lo(), &lmax = c->*CompoundBoxAccess::hi();
  half = btScalar(0.5) * (lmax - lmin);
  centre = btScalar(0.5) * (lmax + lmin);
  if (!c->getNumChildShapes()) {
    half.setValue(0, 0, 0);
    centre.setValue(0, 0, 0);
  }
  half += btVector3(c->getMargin(), c->getMargin(), c->getMargin());
  set = true;
}

namespace {

std::shared_ptr<const ModelSweepInfo> model_sweep_info(Object &robot) {
  if (robot.sweep_links) return std::static_pointer_cast<const ModelSweepInfo>(robot.sweep_links);
  const Model &md = *robot.model;
  std::lock_guard<std::mutex> lock(md.cache_mu);
  auto info = std::static_pointer_cast<const ModelSweepInfo>(md.sweep_links);
  bool ok = info && info->links.size() == robot.link_rb.size();
  for (size_t l = 0; ok && l < robot.link_rb.size(); ++l)
    ok = (robot.link_rb[l] ? robot.link_rb[l]->getCollisionShape() : nullptr) == info->links[l].shape;
  if (ok) {
    robot.sweep_links = info;
    return info;
  }
  auto fresh = std::make_shared<ModelSweepInfo>();
  fresh->links.resize(robot.link_rb.size());
  for (size_t l = 0; l < robot.link_rb.size(); ++l) {
    if (!robot.link_rb[l]) continue;
    LinkInfo &li = fresh->links[l];
    li.shape = robot.link_rb[l]->getCollisionShape();
    link_chain(md, (int)l, li.chain);
    for (int j : li.chain)
      if (j < 256) li.chain_bits[j >> 6] |= uint64_t(1) << (j & 63);
    collect_pieces(li.shape, btTransform::getIdentity(), li.pieces, fresh->owned);
    li.radius = shape_radius(li.shape);
    if (li.shape->isCompound()) li.box.take(static_cast<const btCompoundShape *>(li.shape));
  }
  md.sweep_links = fresh;
  robot.sweep_links = fresh;
  return fresh;
}

}  // namespace

namespace sweep {

double link_gap(Object &o, int link, const btCollisionObject *other, double maxd) {
  if (!o.sweep_links) model_sweep_info(o);
  const LinkInfo &li = static_cast<const ModelSweepInfo *>(o.sweep_links.get())->links[link];
  return pieces_distance(li.pieces, o.link_rb[link]->getWorldTransform(), other, maxd);
}

Scratch &scratch() {
  static Scratch s;  // under the API lock
  return s;
}

// The base (or body) poses at the ends, then the joint changes (q0, q1 set before).
void Sweep::set_ends(const btTransform &a, const btTransform &b) {
  set_base(a, b);
  prepare();
}

Object &Sweep::set_robot_motion(int rh, const double *base_from7, const double *q_from,
                                const double *base_to7, const double *q_to, int nq) {
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
  robot = &r;
  q0.assign(q_from, q_from + nj);
  q1.assign(q_to, q_to + nj);
  set_ends(b0, b1);
  return r;
}

void Sweep::set_base(const btTransform &a, const btTransform &b) {
  base0 = a;
  base1 = b;
  rot0 = a.getRotation();
  rot1 = b.getRotation();
  if (rot0.dot(rot1) < 0) rot1 = -rot1;
  angle = rot0.angleShortestPath(rot1);
}

Mover &Sweep::add_mover(int obj, int link, const btCollisionObject *co, int frame_link,
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
void Sweep::add_body_mover(int obj, const btCollisionObject *co, int frame_link, const btTransform &rel,
                           std::vector<int> chain) {
  body_chains.push_back(std::make_unique<std::vector<int>>(std::move(chain)));
  body_pieces.push_back(std::make_unique<std::vector<Piece>>());
  const btCollisionShape *s = co->getCollisionShape();
  collect_pieces(s, btTransform::getIdentity(), *body_pieces.back(), owned);
  add_mover(obj, -1, co, frame_link, rel, body_chains.back().get(), *body_pieces.back(),
            shape_radius(s));
}

// Rigidly attached bodies of PARENT (and theirs), hanging from FRAME_LINK at REL.
void Sweep::add_attached(int parent, int frame_link, const btTransform &rel, int depth) {
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

// The largest distance from the line through the origin of a frame along the unit AXIS to a
// point of mover M, whose frame is at REL in that frame (from its pieces' boxes in that frame).
static double axis_reach(const Mover &m, const btTransform &rel, const btVector3 &axis) {
  double r2 = 0;
  for (const Piece &p : m.pieces) {
    btVector3 lo, hi;
    p.shape->getAabb(rel * p.local, lo, hi);
    for (int k = 0; k < 8; ++k) {
      btVector3 c((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
      r2 = std::max(r2, (double)(c - axis * c.dot(axis)).length2());
    }
  }
  return std::sqrt(r2) + 1e-9;
}

// W and B of every mover over the whole move (see the file comment), from the chain of its
// movable joints: the distance between consecutive joint origins is fixed for revolute joints
// and convex in the value of a prismatic one, so its larger end value bounds it.
void Sweep::bound_movers(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1) {
  double dtrans = (base1.getOrigin() - base0.getOrigin()).length();
  // a robot turning on the spot about the vertical, its joints kept
  bool turn_in_place = robot && base0.getOrigin() == base1.getOrigin() && rot0.x() == 0 &&
                       rot0.y() == 0 && rot1.x() == 0 && rot1.y() == 0 && q0 == q1;
  sc.rates.clear();
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
    m.r0 = (int)sc.rates.size();
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
      bool prismatic = robot->model->joints[j].type == CN_JOINT_PRISMATIC;
      if (prismatic) {
        B += d;
      } else {
        W += d;
        B += d * reach;
      }
      sc.rates.push_back({j, prismatic, d, reach});
    }
    reach += std::max((p0 - base0.getOrigin()).length(), (p1 - base1.getOrigin()).length());
    B += angle * reach;
    m.nr = (int)sc.rates.size() - m.r0;
    m.reach = reach;
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

// Tighter bounds for the search of the movers that meet something (nc > 0), from the rates
// bound_movers noted: A, a bound on their points' acceleration, the joints' and the base's
// rates being constant (a revolute joint's term is its rate times how fast its axis turns and
// its points move relative to its origin: 2 x the rotation above it x its reach, plus the
// speeds below it; a prismatic joint's its rate times how fast its axis turns; the base
// rotation's, about a fixed axis through the base origin, its rate times the speed), never
// above 3 W B; and Bp, a speed bound for clearing intervals (the grid of the search keeps B):
// the turn of the joint nearest the mover that changes, or of the base when none does, moves
// the mover's points at its rate times their distance from its axis (which that turn keeps),
// not their distance from its origin.
void Sweep::tighten_bounds(const std::vector<btTransform> &lp0) {
  for (Mover &m : movers) {
    if (m.nc == 0) continue;
    const Rate *rates = sc.rates.data() + m.r0;
    int nr = m.nr;
    double W = m.W, B = m.B;
    double A = 0, S = 0, below = 0;  // S: speed bound of the joints from the mover up to here
    for (int r = 0; r < nr; ++r) {
      const Rate &x = rates[r];
      if (x.prismatic) {
        S += x.d;
        A += x.d * (W - below);
      } else {
        S += x.d * x.reach;
        below += x.d;
        A += x.d * (2 * (W - below) * x.reach + S);
      }
    }
    S += angle * m.reach;
    A += angle * S;
    m.A = std::min(A, 3 * W * B);
    double Bp = B;
    btTransform mover0 = (robot && m.frame_link >= 0 ? lp0[m.frame_link] : base0) * m.rel;
    int r = 0;
    while (r < nr && rates[r].d == 0) ++r;
    if (r < nr && !rates[r].prismatic) {
      const JointM &jm = robot->model->joints[rates[r].joint];
      Bp = B - rates[r].d * (rates[r].reach - axis_reach(m, lp0[jm.child].inverseTimes(mover0), jm.axis.normalized()));
    } else if (r == nr && angle > 0) {
      Bp = B - angle * (m.reach - axis_reach(m, base0.inverseTimes(mover0), (rot0.inverse() * rot1).getAxis()));
    }
    m.Bp = Bp > 0 && Bp < B ? Bp : B;
  }
}

// The first joint on CHAIN whose value changes in this move (its own value or the one it
// mimics differs between the ends), when the base stays and that joint is revolute: its origin
// does not move. -1 otherwise.
int Sweep::first_changing(const std::vector<int> &chain) const {
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

// needed: the links LINK_OF(mover) gives and the links on their way from the root.
template <class F>
void Sweep::mark_needed(F link_of) {
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
void Sweep::set_anchors(const std::vector<btTransform> &lp0) {
  any_anchor = false;
  anchors.clear();
  for (Mover &m : movers) {
    m.anchor = -1;
    m.anchor_ix = 0;
    if (!robot || m.frame_link < 0) {
      m.rel_anchor = m.rel;
      continue;
    }
    for (int j : *m.chain)
      if (dv[j] != 0) m.anchor = robot->model->joints[j].child;
    any_anchor |= m.anchor >= 0;
    m.rel_anchor = (m.anchor >= 0 ? lp0[m.anchor] : base0).inverseTimes(lp0[m.frame_link] * m.rel);
    if (m.anchor >= 0) {
      auto it = std::find(anchors.begin(), anchors.end(), m.anchor);
      m.anchor_ix = 1 + (int)(it - anchors.begin());
      if (it == anchors.end()) anchors.push_back(m.anchor);
    }
  }
}

// The joints whose child links fk computes: all those needed, and those a changing joint moves.
void Sweep::plan_fk() {
  const Model &md = *robot->model;
  std::vector<char> &moved = sc.moved;
  moved.assign(md.links.size(), 0);
  fk_joints.clear();
  fk_moving.clear();
  fk_primed = false;
  for (size_t j = 0; j < md.joints.size(); ++j) {  // parents before children
    const JointM &jm = md.joints[j];
    moved[jm.child] = moved[jm.parent] || dv[j] != 0;
    if (!needed[jm.child]) continue;
    fk_joints.push_back((int)j);
    if (moved[jm.child]) fk_moving.push_back((int)j);
  }
}

// The joint changes, once the ends are set.
void Sweep::prepare() {
  base_moves = (base1.getOrigin() - base0.getOrigin()).length2() > 0 || angle > 0;
  if (!robot) return;
  const Model &md = *robot->model;
  dv.assign(q0.size(), 0);
  moving_bits = {};
  for (size_t j = 0; j < q0.size(); ++j) {
    dv[j] = model_joint_value(md, q1, (int)j) - model_joint_value(md, q0, (int)j);
    if (dv[j] != 0) {
      if (j < 256) moving_bits[j >> 6] |= uint64_t(1) << (j & 63);
      else many_joints = true;
    }
  }
}

// The link poses (those NEEDED) for BASE and joint values Q: the robot's own when it stands so
// (the same computation made them), else computed into OUT.
const std::vector<btTransform> &Sweep::end_link_poses(const btTransform &base, const std::vector<double> &q,
                                                      std::vector<btTransform> &out) {
  if (base == robot->base && q == robot->q && robot->link_pose.size() == robot->model->links.size())
    return robot->link_pose;
  compute_link_poses(*robot->model, base, q, out, &needed);
  return out;
}

void Sweep::run(double max_step) {
  // the boxes of what the movers may meet; the robot's and the carried objects' own boxes
  // are not read (they are left out of the candidates)
  sync_aabbs_except(w, [&](int ob) { return (robot && ob == robot->id) || moving(ob); });
  const std::vector<btTransform> *ends[2] = {&sc.lp0, &sc.lp1};
  if (robot) {  // the poses at the ends of the links the movers hang from
    mark_needed([](const Mover &m) { return m.frame_link; });
    ends[0] = &end_link_poses(base0, q0, sc.lp0);
    ends[1] = &end_link_poses(base1, q1, sc.lp1);
  }
  const std::vector<btTransform> &lp0 = *ends[0], &lp1 = *ends[1];
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
    lp.resize(robot->model->links.size());  // fk computes every link it reads the first time
    plan_fk();
  }
  double n_real = std::ceil(std::max(total_rot, total_trans) / max_step);
  if (n_real > 1e5)
    fail(CN_E_ARG, "the move needs %.0f sub-steps of at most %s, more than 100000: raise the maximum step",
         n_real, num(max_step).c_str());
  levels = 0;
  while ((double)(1 << levels) < n_real) ++levels;
  n = 1 << levels;
  gather_candidates(lp0, lp1);
  tighten_bounds(lp0);
  point_slot.assign(n + 1, -1);
  time_poses.clear();
  time_index.clear();
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
    if (reference)
      descend_reference(i, 0, n, 0);
    else
      descend(i, 0, n, 0);
  }
}

}  // namespace sweep

namespace {

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
  if (flags & ~(CN_SWEEP_SKIP_START_CONTACTS | CN_SWEEP_REFERENCE))
    fail(CN_E_ARG, "sweep flags %d, expected a sum of %d and %d", flags, CN_SWEEP_SKIP_START_CONTACTS,
         CN_SWEEP_REFERENCE);
  check_output(cap, o4, "contact output");
  check_output(cap, od, "fraction and point output");
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
using namespace cn::sweep;

extern "C" {

int cn_robot_sweep_check(int wh, int rh, const double *base_from7, const double *q_from,
                         const double *base_to7, const double *q_to, int nq, const int *ignore4,
                         int n_ignore, double max_step, double tolerance, int flags, int *out4,
                         double *outd, int cap) {
  return guard([&] {
    World &w = world(wh);
    check_common(w, ignore4, n_ignore, max_step, tolerance, flags, cap, out4, outd);
    std::unique_ptr<Sweep> s(new Sweep(w, ignore4, n_ignore, tolerance, flags));
    Object &r = s->set_robot_motion(rh, base_from7, q_from, base_to7, q_to, nq);
    s->info = model_sweep_info(r);
    s->movers.reserve(r.link_rb.size() + w.attachments.size());
    for (size_t l = 0; l < r.link_rb.size(); ++l) {
      if (!r.link_rb[l]) continue;
      const LinkInfo &li = s->info->links[l];
      if (s->link_moves(li))
        s->add_mover(rh, (int)l, r.link_rb[l], (int)l, btTransform::getIdentity(), &li.chain,
                     li.pieces, li.radius).box = &li.box;
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

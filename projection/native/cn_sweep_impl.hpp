// The state and steps of one sweep check (struct Sweep), shared by cn_sweep.cpp (the ends, the
// movers and their bounds, run, the entry points) and cn_sweep_steps.cpp (candidates, the time
// hierarchy, confirmation by distances). The method is described at the top of cn_sweep.cpp and
// cn_sweep_steps.cpp.
#pragma once
#include "cn_sweep.hpp"

namespace cn {
namespace sweep {

// The working arrays of the sweeps (cn_sweep.cpp).
Scratch &scratch();

struct Sweep {
  World &w;
  Scratch &sc = scratch();
  const Object *robot = nullptr;            // null for a body sweep
  btTransform base0, base1;
  btQuaternion rot0, rot1;
  double angle = 0;                          // base rotation over the move
  std::vector<double> &q0 = sc.q0, &q1 = sc.q1, &qt = sc.qt, &dv = sc.dv;  // dv: joint value changes (mimic applied)
  std::vector<char> &needed = sc.needed;
  std::vector<btTransform> &lp = sc.lp;      // link poses at the time asked last
  std::vector<Mover> &movers = sc.movers;
  std::shared_ptr<const ModelSweepInfo> info;            // the robot's links (model_sweep_info)
  std::vector<std::unique_ptr<std::vector<Piece>>> body_pieces;  // pieces of moving bodies
  std::vector<std::unique_ptr<std::vector<int>>> body_chains;    // chains of attached bodies
  // the movers' candidates, side by side (Mover::c0, nc): the bodies, their broadphase boxes,
  // whether a pair is done (reported, or left out as a start contact) and the time before
  // which it cannot be reached
  std::vector<Cand> &cand = sc.cand;
  std::vector<std::unique_ptr<btCollisionShape>> owned;  // boxes standing in for concave pieces
  std::vector<int> &moving_ids = sc.moving_ids;          // the robot and what it carries
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
  std::vector<Hit> &hits = sc.hits;

  Sweep(World &wd, const int *ign, int n_ign, double tolerance, int flags)
      : w(wd), ignore4(ign), n_ignore(n_ign), tol(tolerance),
        skip_start((flags & CN_SWEEP_SKIP_START_CONTACTS) != 0),
        reference((flags & CN_SWEEP_REFERENCE) != 0) {
    for (auto *v : {&q0, &q1, &qt, &dv}) v->clear();
    movers.clear();
    moving_ids.clear();
    hits.clear();
  }

  void set_ends(const btTransform &a, const btTransform &b);

  // The robot rh of the world and its motion from (base_from7, q_from) to (base_to7, q_to)
  // (nq joint values each, every joint of the robot), checked, as this sweep's ends.
  Object &set_robot_motion(int rh, const double *base_from7, const double *q_from,
                           const double *base_to7, const double *q_to, int nq);

  void set_base(const btTransform &a, const btTransform &b);

  btTransform base_at(double t) const {
    btQuaternion r = angle > 1e-12 ? rot0.slerp(rot1, t) : rot0;
    return btTransform(r, base0.getOrigin().lerp(base1.getOrigin(), t));
  }

  // The frame of mover M at time T, from the base and the links the movers hang from (their
  // anchors, see run) there, computed once per time (at_time).
  btTransform pose_at(const Mover &m, double t) {
    return time_poses[at_time(t) + m.anchor_ix] * m.rel_anchor;
  }

  // The entry in time_poses of the base's and the anchors' poses at time T (computed when first
  // asked for).
  size_t at_time(double t) {
    size_t found = time_index.find(t);
    if (found != SIZE_MAX) return found;
    size_t at = time_poses.size(), na = anchors.size() + 1;
    time_index.insert(t, at);
    time_poses.resize(at + na);
    time_poses[at] = base_at(t);
    if (robot && any_anchor) {
      fk(t, time_poses[at]);
      for (size_t a = 1; a < na; ++a) time_poses[at + a] = lp[anchors[a - 1]];
    }
    return at;
  }

  // The poses of the links the movers hang from at time T (the base there BASE), into lp: the
  // first time all of them, then those a changing joint moves (the others keep their poses
  // while the base stays: the same base pose and joint values give the same poses).
  void fk(double t, const btTransform &base) {
    for (size_t j = 0; j < qt.size(); ++j) qt[j] = q0[j] + t * (q1[j] - q0[j]);
    compute_link_poses_of(*robot->model, base, qt, lp, fk_primed ? fk_moving : fk_joints);
    fk_primed = !base_moves;
  }
  std::vector<int> &fk_joints = sc.fk_joints;  // the joints of the links needed, model order
  std::vector<int> &fk_moving = sc.fk_moving;  // those of them a changing joint moves
  bool fk_primed = false;                       // lp holds every needed link's pose
  void plan_fk();

  Mover &add_mover(int obj, int link, const btCollisionObject *co, int frame_link,
                   const btTransform &rel, const std::vector<int> *chain,
                   const std::vector<Piece> &pieces, double radius);

  void add_body_mover(int obj, const btCollisionObject *co, int frame_link, const btTransform &rel,
                      std::vector<int> chain);

  void add_attached(int parent, int frame_link, const btTransform &rel, int depth);

  void bound_movers(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1);

  void tighten_bounds(const std::vector<btTransform> &lp0);

  int first_changing(const std::vector<int> &chain) const;

  // Whether an ignore pair leaves out every mover's contacts with link HLINK of HOBJ.
  bool ignored_by_all(int hobj, int hlink) const {
    for (int i = 0; i < n_ignore; ++i) {
      const int *r = ignore4 + 4 * i;
      if (r[0] == -1 && r[1] == -1 && (r[2] == -1 || r[2] == hobj) && (r[3] == -1 || r[3] == hlink))
        return true;
    }
    return false;
  }

  void move_box(const Mover &m, const btTransform &t0, const btTransform &t1, btVector3 &lo,
                btVector3 &hi) const;

  void gather_candidates(const std::vector<btTransform> &lp0, const std::vector<btTransform> &lp1);

  bool hull_touches(const Mover &m, const btTransform &ta, const btTransform &tb, double grow,
                    const btCollisionObject *other);

  Closest distance(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other);

  double distance_at(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other);

  bool touches(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other,
               double &d, btVector3 &point);

  double confirm(const Mover &m, const btCollisionObject *other, double ta, const btTransform &pa,
                 double &da, double tb, const btTransform &pb, double &db, int depth, btVector3 &point);

  void report(const Mover &m, const btCollisionObject *other, double t, const btVector3 &point);

  // the reference search (cn_sweep_reference.cpp, flag CN_SWEEP_REFERENCE)
  bool reference = false;
  double distance_reference(const Mover &m, const btTransform &t, double maxd, const btCollisionObject *other,
                            btVector3 *point = nullptr);
  double confirm_reference(const Mover &m, const btCollisionObject *other, double ta, const btTransform &pa,
                           double &da, double tb, const btTransform &pb, double &db, btVector3 &point,
                           int depth);
  void slot_reference(int k);
  void descend_reference(size_t i, int ka, int kb, int depth);

  Cand *kept = nullptr;  // the pair confirm searches in a sub-step, which keeps the distance
  int kept_k = 0;        // at its end (sub-step point kept_k) for the next sub-step

  bool base_moves = false;

  template <class F>
  void mark_needed(F link_of);

  void set_anchors(const std::vector<btTransform> &lp0);

  void prepare();

  std::array<uint64_t, 4> moving_bits{};  // the joints that change, as bits (the first 256)
  bool many_joints = false;               // a joint past the first 256 changes

  // chain_moves for a link's chain, from its bits
  bool link_moves(const LinkInfo &li) const {
    if (base_moves) return true;
    if (many_joints) return chain_moves(li.chain);
    return ((li.chain_bits[0] & moving_bits[0]) | (li.chain_bits[1] & moving_bits[1]) |
            (li.chain_bits[2] & moving_bits[2]) | (li.chain_bits[3] & moving_bits[3])) != 0;
  }

  bool chain_moves(const std::vector<int> &chain) const {
    if (base_moves) return true;
    for (int j : chain)
      if (dv[j] != 0) return true;
    return false;
  }

  // The link poses for BASE and joint values Q (those NEEDED): the robot's own when it stands so,
  // else computed into OUT.
  const std::vector<btTransform> &end_link_poses(const btTransform &base, const std::vector<double> &q,
                                                 std::vector<btTransform> &out);

  void run(double max_step);

  // ---- the time hierarchy: the move's n = 2^levels sub-steps, halved from the whole move
  int levels = 0, n = 1;
  std::vector<int> &point_slot = sc.point_slot;  // sub-step point k -> its slot (-1: none yet)
  int n_slots = 0;
  std::vector<btTransform> &slot_pose = sc.slot_pose;  // per slot, one pose per mover
  std::vector<btVector3> &slot_lo = sc.slot_lo, &slot_hi = sc.slot_hi;  // per slot, one box per mover
  std::vector<std::vector<int>> &pool = sc.pool;        // candidate lists per depth

  std::vector<int> &anchors = sc.anchors;                // distinct anchors (Mover::anchor_ix - 1)
  std::vector<btTransform> &time_poses = sc.time_poses;  // per time asked, 1 + anchors.size() poses
  TimeIndex &time_index = sc.time_index;                 // time -> its poses
  std::vector<size_t> &slot_at = sc.slot_at;             // per slot: its entry in time_poses
  std::vector<char> &slot_have = sc.slot_have;           // per slot and mover

  int slot(int k);

  // The entry of mover I's pose and box at time k / n in slot_pose, slot_lo, slot_hi: computed
  // when first asked for, from the slot's anchor poses.
  size_t slot_entry(int k, size_t i) {
    size_t at = (size_t)slot(k) * movers.size() + i;
    if (!slot_have[at]) {
      const Mover &m = movers[i];
      size_t sl = at / movers.size();
      slot_pose[at] = time_poses[slot_at[sl] + m.anchor_ix] * m.rel_anchor;
      m.aabb(slot_pose[at], slot_lo[at], slot_hi[at]);
      slot_have[at] = 1;
    }
    return at;
  }

  void descend(size_t i, int ka, int kb, int depth);
  bool gather_interval(size_t a, size_t b, double tb, double grow, double path,
                       const std::vector<int> &from, std::vector<int> &keep);
  bool clear_by_hull(const Mover &m, size_t a, size_t b, double ta, double tb, double grow,
                     std::vector<int> &keep);
};

}  // namespace sweep
}  // namespace cn

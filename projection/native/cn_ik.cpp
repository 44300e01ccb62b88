// Kinematic chains of articulated objects: forward kinematics with KDL, inverse kinematics
// with a damped least-squares (Levenberg-Marquardt) solver on the chain's geometric Jacobian.
#include "cn_internal.hpp"
#include "cn_reach_map.hpp"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstring>
#include <unordered_map>

namespace cn {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Jac = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// How a joint value is kept valid: clamped into its limits, wrapped to [-pi, pi] (continuous
// or unlimited revolute joints), or left free (unlimited prismatic joints).
enum class Range { Clamp, Wrap, Free };

// A movable joint of the IK model: the fixed transform (R, p) from the previous joint's moving
// frame (the base link for the first joint) to this joint's frame, then a rotation about or a
// translation along `axis` (unit, in the joint frame).  unit_axis: 0/1/2 when the axis is a
// coordinate axis (sign in unit_sign), else -1.
struct KinJoint {
  Mat3 R;
  Vec3 p;
  Vec3 axis;
  bool prismatic = false;
  int unit_axis = -1;
  double unit_sign = 1;
  Range range = Range::Clamp;
  // what the forward kinematics may leave out (the same numbers: only products with 0 and 1)
  bool R_identity = false;  // R is the identity
  int p_axis = 3;           // p is zero (-1), along one coordinate axis (0..2), or general (3)
};

// The answers of cn_chain_ik that its random restarts play no part in: a goal out of the reach
// map's reach (no attempt is made) and a goal solved from the seed (the first attempt). Kept by
// the bits of the goal, the seed, the restart count and the tolerances, so that a repeated
// question (a pre-check's goals asked again when the motion is made) gets the same answer to the
// last bit without the solver; emptied when it holds kMaxEntries, so that it never grows past
// that.
struct IkMemo {
  static constexpr size_t kMaxEntries = 4096;
  struct Answer {
    std::vector<double> q;
    double err[2];
    int status;
  };
  struct Hash {
    size_t operator()(const std::vector<uint64_t> &k) const {
      uint64_t h = 0x9E3779B97F4A7C15ull;
      for (uint64_t x : k) h = (h ^ x) * 0xBF58476D1CE4E5B9ull, h ^= h >> 31;
      return (size_t)h;
    }
  };
  std::unordered_map<std::vector<uint64_t>, Answer, Hash> answers;
  static std::vector<uint64_t> key(const double *target7, const double *seed, size_t n,
                                   int max_restarts, double pos_tol, double rot_tol) {
    std::vector<uint64_t> k(7 + n + 3);
    std::memcpy(k.data(), target7, 7 * sizeof(double));
    std::memcpy(k.data() + 7, seed, n * sizeof(double));
    k[7 + n] = (uint64_t)(uint32_t)max_restarts;
    std::memcpy(&k[8 + n], &pos_tol, sizeof(double));
    std::memcpy(&k[9 + n], &rot_tol, sizeof(double));
    return k;
  }
  void keep(std::vector<uint64_t> &&k, const double *q, size_t n, const double *err, int status) {
    if (answers.size() >= kMaxEntries) answers.clear();
    answers[std::move(k)] = Answer{std::vector<double>(q, q + n), {err[0], err[1]}, status};
  }
};

struct Chain {
  ModelP model;
  KDL::Chain chain;
  std::vector<int> joints;          // robot joint index per chain joint
  std::vector<double> lower, upper; // limits (continuous: -pi..pi, unlimited = false)
  std::vector<bool> limited;
  std::vector<KinJoint> kin;        // IK model, one per movable joint
  Mat3 tip_R = Mat3::Identity();    // fixed transform from the last joint's frame to the tip
  Vec3 tip_p = Vec3::Zero();
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<ReachMap> reach;  // where the tip can be: built at the first IK call
  IkMemo memo;                      // answers that do not depend on the random restarts
};

// What the chain's reach map is made of.
std::vector<ReachJoint> reach_joints(const Chain &c) {
  std::vector<ReachJoint> joints(c.kin.size());
  for (size_t i = 0; i < c.kin.size(); ++i) {
    const KinJoint &k = c.kin[i];
    joints[i].R = k.R;
    joints[i].p = k.p;
    joints[i].axis = k.axis;
    joints[i].prismatic = k.prismatic;
    // an unlimited prismatic joint has no range to sample: no map
    joints[i].lower = k.range == Range::Free ? -HUGE_VAL : c.lower[i];
    joints[i].upper = k.range == Range::Free ? HUGE_VAL : c.upper[i];
  }
  return joints;
}

// The chain's reach map, built at the first call (entry points run one at a time).
const ReachMap &reach_map(Chain &c) {
  if (!c.reach) c.reach = std::make_unique<ReachMap>(reach_joints(c), c.tip_p);
  return *c.reach;
}

std::mutex g_chain_mutex;
std::vector<Chain *> g_chains;
std::vector<int> g_chain_gen;
std::vector<int> g_chain_free;

Chain &chain(int h) {
  std::lock_guard<std::mutex> lock(g_chain_mutex);
  int slot = h & 0xffff, gen = h >> 16;
  if (h < 0 || slot >= (int)g_chains.size() || !g_chains[slot] || g_chain_gen[slot] != gen)
    fail(CN_E_HANDLE, "chain handle %d is not a live kinematic chain", h);
  return *g_chains[slot];
}

KDL::Frame to_kdl(const btTransform &t) {
  btQuaternion q = t.getRotation();
  const btVector3 &p = t.getOrigin();
  return KDL::Frame(KDL::Rotation::Quaternion(q.x(), q.y(), q.z(), q.w()),
                    KDL::Vector(p.x(), p.y(), p.z()));
}

void frame_to_pose(const KDL::Frame &f, double *out) {
  double x, y, z, w;
  f.M.GetQuaternion(x, y, z, w);
  out[0] = f.p.x(); out[1] = f.p.y(); out[2] = f.p.z();
  out[3] = x; out[4] = y; out[5] = z; out[6] = w;
}

void read_q(const Chain &c, const double *q, KDL::JntArray &out, const char *what) {
  check_ptr(q, what);
  out.resize(c.joints.size());
  for (size_t i = 0; i < c.joints.size(); ++i) {
    if (!std::isfinite(q[i]))
      fail(CN_E_ARG, "%s has %s for joint '%s' (element %d)", what, num(q[i]).c_str(),
           c.model->joints[c.joints[i]].name.c_str(), (int)i);
    out(i) = q[i];
  }
}

Mat3 rot_matrix(const btTransform &t) {
  const btMatrix3x3 &b = t.getBasis();
  Mat3 m;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) m(r, k) = b[r][k];
  return m;
}

Vec3 position(const btTransform &t) {
  const btVector3 &o = t.getOrigin();
  return Vec3(o.x(), o.y(), o.z());
}

// Rotation vector (unit axis times angle, angle in [0, pi]) of the rotation matrix d.
Vec3 rot_log(const Mat3 &d, double &angle) {
  Vec3 v(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));  // 2 sin(angle) axis
  double s = 0.5 * v.norm(), co = 0.5 * (d.trace() - 1);
  angle = std::atan2(s, co);
  if (s > 1e-7) return v * (angle / (2 * s));
  if (co > 0) return 0.5 * v;
  // near a half turn: the symmetric part is cos(angle) I + (1 - cos(angle)) axis axis^T
  Mat3 sym = 0.5 * (d + d.transpose());
  int i;
  sym.diagonal().maxCoeff(&i);
  Vec3 axis = (sym.col(i) - co * Vec3::Unit(i)) / std::sqrt(std::max(1e-300, sym(i, i) - co) * (1 - co));
  axis.normalize();
  if (axis.dot(v) < 0) axis = -axis;
  return axis * angle;
}

// R := R * rotation of the joint by q
void rotate_by(const KinJoint &k, double q, Mat3 &R) {
  if (k.unit_axis < 0) {
    R = R * Eigen::AngleAxisd(q, k.axis).toRotationMatrix();
    return;
  }
  double s = std::sin(k.unit_sign * q), c = std::cos(k.unit_sign * q);
  int b = (k.unit_axis + 1) % 3, d = (k.unit_axis + 2) % 3;
  Vec3 cb = R.col(b), cd = R.col(d);
  R.col(b) = c * cb + s * cd;
  R.col(d) = c * cd - s * cb;
}

// Tip pose (R, p) in the base frame for joint values q; with J, also the geometric Jacobian
// (rows: linear velocity of the tip, angular velocity times `rot_weight`; base frame).
void kin_fk(const Chain &c, const double *q, Mat3 &R, Vec3 &p, Jac *J, double rot_weight) {
  R.setIdentity();
  p.setZero();
  const size_t n = c.kin.size();
  for (size_t i = 0; i < n; ++i) {
    const KinJoint &k = c.kin[i];
    if (k.p_axis == 3)
      p += R * k.p;
    else if (k.p_axis >= 0)
      p += R.col(k.p_axis) * k.p(k.p_axis);
    if (!k.R_identity) R = R * k.R;
    Vec3 z = k.unit_axis >= 0 ? Vec3(k.unit_sign * R.col(k.unit_axis)) : Vec3(R * k.axis);
    if (k.prismatic) {
      p += z * q[i];
      if (J) J->col(i) << z, Vec3::Zero();
    } else {
      if (J) J->col(i) << p, z;  // joint origin for now, turned into z x (tip - origin) below
      rotate_by(k, q[i], R);
    }
  }
  p += R * c.tip_p;
  R = R * c.tip_R;
  if (J)
    for (size_t i = 0; i < n; ++i)
      if (!c.kin[i].prismatic) {
        Vec3 o = J->col(i).head<3>(), z = J->col(i).tail<3>();
        J->col(i).head<3>() = z.cross(p - o);
      }
  if (J) J->bottomRows<3>() *= rot_weight;
}

// q within the joint ranges: limited joints clamped, revolute joints without limits wrapped.
void keep_in_range(const Chain &c, double *q) {
  for (size_t i = 0; i < c.kin.size(); ++i) switch (c.kin[i].range) {
      case Range::Clamp: q[i] = std::min(c.upper[i], std::max(c.lower[i], q[i])); break;
      case Range::Wrap: q[i] = std::remainder(q[i], 2 * M_PI); break;
      case Range::Free: break;
    }
}

// A seed brought into the ranges: limited revolute joints first by whole turns, then clamped.
void seed_into_range(const Chain &c, double *q) {
  for (size_t i = 0; i < c.kin.size(); ++i)
    if (c.kin[i].range == Range::Clamp && !c.kin[i].prismatic) {
      while (q[i] > c.upper[i] && q[i] - 2 * M_PI >= c.lower[i]) q[i] -= 2 * M_PI;
      while (q[i] < c.lower[i] && q[i] + 2 * M_PI <= c.upper[i]) q[i] += 2 * M_PI;
    }
  keep_in_range(c, q);
}

// Tuning of the solver.  The rotation error is weighted as if 1 rad were kRotWeight m.
constexpr double kRotWeight = 0.4;
constexpr int kMaxIterations = 40;   // per start
constexpr int kStallWindow = 6;      // a start is given up when the error has not dropped
constexpr double kStallRatio = 0.9;  // below kStallRatio of its value kStallWindow steps ago
constexpr double kDampFloor = 1e-10; // damping added to the squared error
constexpr double kMaxStep = 1.0;     // largest joint change in one step (rad or m)
constexpr int kPolishSteps = 3;      // steps spent below the tolerance towards 1/100 of it

struct Errors {
  Vec6 e;              // weighted error: position (m), rotation vector (times kRotWeight)
  double pos2, rot2;   // squared position (m^2) and rotation (rad^2) errors
  double cost;         // squared norm of e
};

void measure(const Mat3 &R, const Vec3 &p, const Mat3 &goal_R, const Vec3 &goal_p, Errors &out) {
  double angle;
  Vec3 w = rot_log(goal_R * R.transpose(), angle);
  Vec3 dp = goal_p - p;
  out.e << dp, kRotWeight * w;
  out.pos2 = dp.squaredNorm();
  out.rot2 = angle * angle;
  out.cost = out.e.squaredNorm();
}

// Per-call work space of the solver (the chain itself is shared and never written).
struct IkSolver {
  const Chain &c;
  Mat3 goal_R;
  Vec3 goal_p;
  double pos2_tol, rot2_tol;
  size_t n;
  Jac J, J_trial, Jm;  // Jacobians at q and at the trial point; J with held joints dropped
  double mu = 1;        // damping factor (times the squared error)
  std::vector<double> q, trial;
  Eigen::VectorXd dq;
  IkSolver(const Chain &ch, const Mat3 &gR, const Vec3 &gp, double pos_tol, double rot_tol)
      : c(ch), goal_R(gR), goal_p(gp), pos2_tol(pos_tol * pos_tol), rot2_tol(rot_tol * rot_tol),
        n(ch.kin.size()), J(6, n), J_trial(6, n), Jm(6, n), q(n), trial(n), dq(n) {}

  bool within(const Errors &e, double scale2) const {
    return e.pos2 <= pos2_tol * scale2 && e.rot2 <= rot2_tol * scale2;
  }

  // The damped least-squares step dq for the error err.  Joints resting on a limit that the
  // step would push further out are held still (their columns dropped) and the step solved
  // again, so that the other joints take over their share of the motion.
  void step(const Errors &err) {
    double damping = mu * err.cost + kDampFloor;
    Jm = J;
    for (int pass = 0; pass < 3; ++pass) {
      Mat6 A = Jm * Jm.transpose();
      A.diagonal().array() += damping;
      Vec6 y = A.llt().solve(err.e);
      dq.noalias() = Jm.transpose() * y;
      bool held = false;
      for (size_t i = 0; i < n; ++i)
        if (c.kin[i].range == Range::Clamp && dq(i) != 0 &&
            ((q[i] <= c.lower[i] && dq(i) < 0) || (q[i] >= c.upper[i] && dq(i) > 0))) {
          Jm.col(i).setZero();
          held = true;
        }
      if (!held) break;
    }
    for (size_t i = 0; i < n; ++i)
      if (c.kin[i].range == Range::Clamp &&
          ((q[i] <= c.lower[i] && dq(i) < 0) || (q[i] >= c.upper[i] && dq(i) > 0)))
        dq(i) = 0;
    double big = dq.cwiseAbs().maxCoeff();
    if (big > kMaxStep) dq *= kMaxStep / big;
  }

  // Levenberg-Marquardt from start (within the ranges); leaves the best joint values of this
  // start in q and their errors in err.  Returns true when they are within the tolerances.
  bool descend(const double *start, Errors &err) {
    std::copy(start, start + n, q.begin());
    Mat3 R;
    Vec3 p;
    kin_fk(c, q.data(), R, p, &J, kRotWeight);
    measure(R, p, goal_R, goal_p, err);
    double history[kStallWindow];
    int polish = 0;
    mu = 1;
    for (int it = 0; it < kMaxIterations; ++it) {
      if (within(err, 1)) {
        if (within(err, 1e-4) || polish++ >= kPolishSteps) return true;
      }
      history[it % kStallWindow] = err.cost;
      if (it >= kStallWindow && err.cost > kStallRatio * history[(it + 1) % kStallWindow] &&
          !within(err, 1))
        return false;
      step(err);
      for (size_t i = 0; i < n; ++i) trial[i] = q[i] + dq(i);
      keep_in_range(c, trial.data());
      kin_fk(c, trial.data(), R, p, &J_trial, kRotWeight);
      Errors te;
      measure(R, p, goal_R, goal_p, te);
      if (te.cost < err.cost) {
        q.swap(trial);
        J.swap(J_trial);
        err = te;
        mu = std::max(0.25 * mu, 1e-3);
      } else {
        mu *= 8;
      }
    }
    return within(err, 1);
  }
};

}  // namespace
}  // namespace cn

using namespace cn;

extern "C" {

int cn_chain_create(int wh, int r, const char *base, const char *tip) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    std::string b = check_str(base, "base link name"), t = check_str(tip, "tip link name");
    const Model &m = *o.model;
    auto bi = m.link_index.find(b), ti = m.link_index.find(t);
    if (bi == m.link_index.end())
      fail(CN_E_NAME, "unknown link '%s' in robot %d ('%s')", b.c_str(), r, m.name.c_str());
    if (ti == m.link_index.end())
      fail(CN_E_NAME, "unknown link '%s' in robot %d ('%s')", t.c_str(), r, m.name.c_str());
    std::vector<int> path;  // joints from tip up to base
    int l = ti->second;
    while (l != bi->second) {
      int j = m.links[l].parent_joint;
      if (j < 0) fail(CN_E_NAME, "link '%s' is not an ancestor of link '%s'", b.c_str(), t.c_str());
      path.push_back(j);
      l = m.joints[j].parent;
    }
    std::reverse(path.begin(), path.end());
    auto c = std::make_unique<Chain>();
    c->model = o.model;
    btTransform fixed = btTransform::getIdentity();  // fixed joints since the last movable one
    for (int j : path) {
      const JointM &jm = m.joints[j];
      KDL::Frame f = to_kdl(jm.origin);
      KDL::Vector axis = f.M * KDL::Vector(jm.axis.x(), jm.axis.y(), jm.axis.z());
      KDL::Joint kj(jm.name + "_fixed", KDL::Joint::None);
      if (jm.type == CN_JOINT_REVOLUTE || jm.type == CN_JOINT_CONTINUOUS)
        kj = KDL::Joint(jm.name, f.p, axis, KDL::Joint::RotAxis);
      else if (jm.type == CN_JOINT_PRISMATIC)
        kj = KDL::Joint(jm.name, f.p, axis, KDL::Joint::TransAxis);
      c->chain.addSegment(KDL::Segment(m.links[jm.child].name, kj, f));
      if (kj.getType() != KDL::Joint::None) {
        c->joints.push_back(j);
        bool lim = jm.type != CN_JOINT_CONTINUOUS && jm.upper > jm.lower;
        c->limited.push_back(lim);
        c->lower.push_back(lim ? jm.lower : -M_PI);
        c->upper.push_back(lim ? jm.upper : M_PI);
        KinJoint k;
        btTransform t = fixed * jm.origin;
        k.R = rot_matrix(t);
        k.p = position(t);
        k.axis = Vec3(jm.axis.x(), jm.axis.y(), jm.axis.z());
        if (!(k.axis.norm() > 1e-12))
          fail(CN_E_PARSE, "joint '%s' has a zero axis", jm.name.c_str());
        k.axis.normalize();
        k.prismatic = jm.type == CN_JOINT_PRISMATIC;
        for (int a = 0; a < 3; ++a)
          if (k.axis((a + 1) % 3) == 0 && k.axis((a + 2) % 3) == 0) {
            k.unit_axis = a;
            k.unit_sign = k.axis(a) > 0 ? 1 : -1;
          }
        k.range = lim ? Range::Clamp : k.prismatic ? Range::Free : Range::Wrap;
        k.R_identity = k.R == Mat3::Identity();
        int nonzero = 0;
        for (int a = 0; a < 3; ++a)
          if (k.p(a) != 0) ++nonzero, k.p_axis = a;
        if (nonzero == 0) k.p_axis = -1;
        if (nonzero > 1) k.p_axis = 3;
        c->kin.push_back(k);
        fixed = btTransform::getIdentity();
      } else {
        fixed = fixed * jm.origin;
      }
    }
    c->tip_R = rot_matrix(fixed);
    c->tip_p = position(fixed);
    if (c->joints.empty())
      fail(CN_E_NAME, "chain from '%s' to '%s' has no movable joint", b.c_str(), t.c_str());
    c->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(c->chain);
    std::lock_guard<std::mutex> lock(g_chain_mutex);
    int slot;
    if (!g_chain_free.empty()) {
      slot = g_chain_free.back();
      g_chain_free.pop_back();
    } else {
      if (g_chains.size() >= 0xffff) fail(CN_E_STATE, "too many live chains");
      slot = (int)g_chains.size();
      g_chains.push_back(nullptr);
      g_chain_gen.push_back(0);
    }
    g_chain_gen[slot] = (g_chain_gen[slot] % 32767) + 1;
    g_chains[slot] = c.release();
    return (g_chain_gen[slot] << 16) | slot;
  });
}

int cn_chain_destroy(int h) {
  return guard([&] {
    Chain *c = &chain(h);
    std::lock_guard<std::mutex> lock(g_chain_mutex);
    int slot = h & 0xffff;
    g_chains[slot] = nullptr;
    g_chain_free.push_back(slot);
    delete c;
    return 0;
  });
}

int cn_chain_num_joints(int h) {
  return guard([&] { return (int)chain(h).joints.size(); });
}

int cn_chain_joints(int h, int *out) {
  return guard([&] {
    Chain &c = chain(h);
    check_ptr(out, "joint output");
    for (size_t i = 0; i < c.joints.size(); ++i) out[i] = c.joints[i];
    return (int)c.joints.size();
  });
}

int cn_chain_limits(int h, double *lo, double *hi) {
  return guard([&] {
    Chain &c = chain(h);
    check_ptr(lo, "lower limit output");
    check_ptr(hi, "upper limit output");
    for (size_t i = 0; i < c.joints.size(); ++i) { lo[i] = c.lower[i]; hi[i] = c.upper[i]; }
    return (int)c.joints.size();
  });
}

int cn_chain_may_reach(int h, const double *position3, double pos_tol) {
  return guard([&] {
    Chain &c = chain(h);
    check_ptr(position3, "position");
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(position3[i])) fail(CN_E_ARG, "position has %s", num(position3[i]).c_str());
    check_positive(pos_tol, "position tolerance");
    return reach_map(c).may_reach(Vec3(position3[0], position3[1], position3[2]), pos_tol) ? 1 : 0;
  });
}

int cn_chain_reach_map_get(int h, double *out_params, unsigned char *out_cells, int cap) {
  return guard([&] {
    Chain &c = chain(h);
    check_ptr(out_params, "parameter output");
    if (cap < 0) fail(CN_E_ARG, "capacity %d", cap);
    if (cap > 0) check_ptr(out_cells, "cell output");
    const ReachMap &m = reach_map(c);
    m.save(reach_joints(c), c.tip_p, out_params);
    const std::vector<unsigned char> &cells = m.cells();
    if (cap > 0) std::memcpy(out_cells, cells.data(), std::min(cells.size(), (size_t)cap));
    return (int)cells.size();
  });
}

int cn_chain_reach_map_set(int h, const double *params, const unsigned char *cells, int n) {
  return guard([&] {
    Chain &c = chain(h);
    check_ptr(params, "parameters");
    if (n < 0) fail(CN_E_ARG, "cell count %d", n);
    if (n > 0) check_ptr(cells, "cells");
    std::unique_ptr<ReachMap> m = ReachMap::restore(reach_joints(c), c.tip_p, params, cells, n);
    if (!m) return 0;
    c.reach = std::move(m);
    c.memo.answers.clear();  // its verdicts on goals out of reach came from the old map
    return 1;
  });
}

int cn_chain_fk(int h, const double *q, double *out7) {
  return guard([&] {
    Chain &c = chain(h);
    KDL::JntArray jq;
    read_q(c, q, jq, "joint values");
    check_ptr(out7, "pose output");
    KDL::Frame f;
    if (c.fk->JntToCart(jq, f) < 0) fail(CN_E_INTERNAL, "KDL forward kinematics failed");
    frame_to_pose(f, out7);
    return 0;
  });
}

int cn_chain_ik(int h, const double *target7, const double *seed, int max_restarts,
                double pos_tol, double rot_tol, unsigned int rng_seed, double *out_q,
                double *out_err) {
  return guard([&] {
    Chain &c = chain(h);
    btTransform t = read_pose(target7, "target pose");
    KDL::JntArray q0;
    read_q(c, seed, q0, "seed joint values");
    check_ptr(out_q, "joint output");
    if (max_restarts < 0) fail(CN_E_ARG, "max restarts %d, expected >= 0", max_restarts);
    check_positive(pos_tol, "position tolerance");
    check_positive(rot_tol, "rotation tolerance");
    const size_t n = c.joints.size();
    std::vector<uint64_t> key = IkMemo::key(target7, seed, n, max_restarts, pos_tol, rot_tol);
    auto known = c.memo.answers.find(key);
    if (known != c.memo.answers.end()) {
      const IkMemo::Answer &a = known->second;
      std::copy(a.q.begin(), a.q.end(), out_q);
      if (out_err) {
        out_err[0] = a.err[0];
        out_err[1] = a.err[1];
      }
      return a.status;
    }
    IkSolver solver(c, rot_matrix(t), position(t), pos_tol, rot_tol);
    std::vector<double> start(n), best(n);
    for (size_t i = 0; i < n; ++i) start[i] = q0(i);
    seed_into_range(c, start.data());
    best = start;
    SplitMix64 rng{rng_seed};  // restarts depend on the rng seed only
    Errors err, best_err;
    best_err.cost = HUGE_VAL;
    // a goal out of the arm's reach: the seed is the best there is, without a single step
    const int attempts = reach_map(c).may_reach(position(t), pos_tol) ? max_restarts + 1 : 0;
    int solved_at = -1;
    for (int attempt = 0; attempt < attempts; ++attempt) {
      if (attempt > 0)
        for (size_t i = 0; i < n; ++i) start[i] = rng.uniform(c.lower[i], c.upper[i]);
      bool ok = solver.descend(start.data(), err);
      if (ok || err.cost < best_err.cost) {
        best = solver.q;
        best_err = err;
      }
      if (ok) {
        solved_at = attempt;
        break;
      }
    }
    // the answer is judged with the same forward kinematics as cn_chain_fk
    KDL::JntArray qb(n);
    for (size_t i = 0; i < n; ++i) qb(i) = out_q[i] = best[i];
    KDL::Frame f;
    if (c.fk->JntToCart(qb, f) < 0) fail(CN_E_INTERNAL, "KDL forward kinematics failed");
    Mat3 R;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) R(r, k) = f.M(r, k);
    double e[2];
    e[0] = (position(t) - Vec3(f.p.x(), f.p.y(), f.p.z())).norm();
    rot_log(rot_matrix(t) * R.transpose(), e[1]);
    if (out_err) {
      out_err[0] = e[0];
      out_err[1] = e[1];
    }
    int status = e[0] <= pos_tol && e[1] <= rot_tol ? 0 : 1;
    if (attempts == 0 || solved_at == 0) c.memo.keep(std::move(key), out_q, n, e, status);
    return status;
  });
}

/* The number of answers the chain's IK memo keeps (see IkMemo), at most IkMemo::kMaxEntries. */
int cn_chain_ik_memo_size(int h) {
  return guard([&] { return (int)chain(h).memo.answers.size(); });
}

}  // extern "C"

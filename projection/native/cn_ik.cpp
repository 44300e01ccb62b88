// Kinematic chains of articulated objects: forward and inverse kinematics with KDL.
#include "cn_internal.hpp"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>

#include <algorithm>
#include <random>

namespace cn {
namespace {

struct Chain {
  ModelP model;
  KDL::Chain chain;
  std::vector<int> joints;          // robot joint index per chain joint
  std::vector<double> lower, upper; // limits (continuous: -pi..pi, unlimited = false)
  std::vector<bool> limited;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainIkSolverPos_LMA> ik;
};

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

// bring q into the limits by whole turns where possible; true if within limits
bool normalize(const Chain &c, KDL::JntArray &q) {
  bool ok = true;
  for (size_t i = 0; i < c.joints.size(); ++i) {
    const JointM &j = c.model->joints[c.joints[i]];
    if (j.type == CN_JOINT_CONTINUOUS) {
      q(i) = std::remainder(q(i), 2 * M_PI);
      continue;
    }
    if (!c.limited[i]) continue;
    if (j.type == CN_JOINT_REVOLUTE) {
      while (q(i) > c.upper[i] + 1e-9 && q(i) - 2 * M_PI >= c.lower[i] - 1e-9) q(i) -= 2 * M_PI;
      while (q(i) < c.lower[i] - 1e-9 && q(i) + 2 * M_PI <= c.upper[i] + 1e-9) q(i) += 2 * M_PI;
    }
    if (q(i) < c.lower[i] - 1e-9 || q(i) > c.upper[i] + 1e-9) ok = false;
  }
  return ok;
}

void errors(const KDL::Frame &a, const KDL::Frame &b, double &pos, double &rot) {
  pos = (a.p - b.p).Norm();
  KDL::Rotation d = a.M.Inverse() * b.M;
  KDL::Vector axis;
  rot = std::fabs(d.GetRotAngle(axis));
}

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
      }
    }
    if (c->joints.empty())
      fail(CN_E_NAME, "chain from '%s' to '%s' has no movable joint", b.c_str(), t.c_str());
    Eigen::Matrix<double, 6, 1> L;
    L << 1, 1, 1, 0.1, 0.1, 0.1;
    c->fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(c->chain);
    c->ik = std::make_unique<KDL::ChainIkSolverPos_LMA>(c->chain, L, 1e-5, 100, 1e-12);
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
    KDL::Frame goal = to_kdl(t);
    std::mt19937 rng(rng_seed);
    const size_t n = c.joints.size();
    KDL::JntArray q(n), best(q0), clamped(n);
    double best_pos = 1e300, best_rot = 1e300;
    bool have_clamped = false, solved = false;
    for (int attempt = 0; attempt <= max_restarts && !solved; ++attempt) {
      KDL::JntArray init(n);
      if (attempt == 0) init = q0;
      else if (have_clamped && attempt % 2 == 1) init = clamped;
      else
        for (size_t i = 0; i < n; ++i)
          init(i) = std::uniform_real_distribution<double>(c.lower[i], c.upper[i])(rng);
      have_clamped = false;
      c.ik->CartToJnt(init, goal, q);
      bool within = normalize(c, q);
      if (!within) {
        clamped = q;
        for (size_t i = 0; i < n; ++i)
          if (c.limited[i]) clamped(i) = std::min(c.upper[i], std::max(c.lower[i], q(i)));
        have_clamped = true;
        continue;
      }
      KDL::Frame f;
      c.fk->JntToCart(q, f);
      double pe, re;
      errors(f, goal, pe, re);
      if (pe + re < best_pos + best_rot) {
        best = q;
        best_pos = pe;
        best_rot = re;
      }
      if (pe <= pos_tol && re <= rot_tol) solved = true;
    }
    for (size_t i = 0; i < n; ++i) out_q[i] = best(i);
    if (out_err) {
      if (best_pos > 1e299) {
        KDL::Frame f;
        c.fk->JntToCart(best, f);
        errors(f, goal, best_pos, best_rot);
      }
      out_err[0] = best_pos;
      out_err[1] = best_rot;
    }
    return solved ? 0 : 1;
  });
}

}  // extern "C"

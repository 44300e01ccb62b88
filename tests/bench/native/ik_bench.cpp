// Inverse kinematics of libcram_native on random reachable poses of the PR2 arms: the tip
// pose of random joint values within the limits is solved from a seed (random within the
// limits, or the middle of the limits) and every answer is checked with the forward
// kinematics and, every 50th pose, by a repeated call (determinism).  With --peer, the same
// kind of poses are also solved by KDL's ChainIkSolverPos_LMA (100 iterations per start,
// random restarts within the limits), built straight from the URDF with urdfdom.
//
// Usage: ik_bench URDF [--poses N] [--restarts R] [--search-dir DIR] [--seed random|middle]
//                      [--tip LINK]... [--peer N] [--machine]
// Human-readable lines by default; with --machine, "name value" lines:
//   ik-mean:TIP seconds, ik-solved:TIP fraction, ik-worst-pos:TIP m, ik-worst-rot:TIP rad,
//   kdl-mean:TIP seconds, kdl-solved:TIP fraction.
// Exits non-zero when an answer disagrees with the forward kinematics, leaves the limits, or
// a repeated call gives a different answer.
#include "cram_native.h"

#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;

namespace {

struct Rng {
  uint64_t s;
  double uniform(double lo, double hi) {
    s += 0x9e3779b97f4a7c15ULL;
    uint64_t z = s;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * ((z >> 11) * 0x1.0p-53);
  }
};

struct Options {
  int poses = 1000, restarts = 200, peer = 0;
  bool random_seed = true, machine = false;
  std::vector<std::string> tips;
};

void pose_errors(const double *a, const double *b, double &pos, double &rot) {
  pos = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                  (a[2] - b[2]) * (a[2] - b[2]));
  double d = std::fabs(a[3] * b[3] + a[4] * b[4] + a[5] * b[5] + a[6] * b[6]);
  rot = 2 * std::acos(std::min(1.0, d));
}

void report(const Options &o, const char *kind, const std::string &tip, int n, int solved,
            std::vector<double> times, double worst_pos, double worst_rot, int mismatches) {
  std::sort(times.begin(), times.end());
  double mean = 0;
  for (double t : times) mean += t;
  mean /= n;
  if (o.machine) {
    printf("%s-mean:%s %.9g\n%s-solved:%s %.6g\n", kind, tip.c_str(), mean, kind, tip.c_str(),
           (double)solved / n);
    if (worst_pos >= 0)
      printf("%s-worst-pos:%s %.6g\n%s-worst-rot:%s %.6g\n", kind, tip.c_str(), worst_pos, kind,
             tip.c_str(), worst_rot);
    return;
  }
  printf("%-4s %-22s %s seeds: %5.1f%% solved, mean %7.1f us, p99 %7.1f us, max %8.1f us",
         kind, tip.c_str(), o.random_seed ? "random" : "middle", 100.0 * solved / n, mean * 1e6,
         times[(size_t)(0.99 * (n - 1))] * 1e6, times.back() * 1e6);
  if (worst_pos >= 0)
    printf(", worst %.2e m %.2e rad, mismatches %d", worst_pos, worst_rot, mismatches);
  printf("\n");
}

// The targets and seeds of pose k (the same for the shim and the peer).
void draw(Rng &rng, const Options &o, const std::vector<double> &lo, const std::vector<double> &hi,
          std::vector<double> &q, std::vector<double> &seed) {
  for (size_t i = 0; i < lo.size(); ++i) q[i] = rng.uniform(lo[i], hi[i]);
  for (size_t i = 0; i < lo.size(); ++i)
    seed[i] = o.random_seed ? rng.uniform(lo[i], hi[i]) : 0.5 * (lo[i] + hi[i]);
}

int run_shim(int world, int robot, const std::string &tip, const Options &o) {
  int ch = cn_chain_create(world, robot, "torso_lift_link", tip.c_str());
  if (ch < 0) {
    fprintf(stderr, "chain to %s: %s\n", tip.c_str(), cn_last_error());
    return 1;
  }
  int nj = cn_chain_num_joints(ch);
  std::vector<double> lo(nj), hi(nj), q(nj), seed(nj), sol(nj), sol2(nj);
  cn_chain_limits(ch, lo.data(), hi.data());
  Rng rng{12345};
  std::vector<double> times;
  int solved = 0, mismatches = 0;
  double worst_pos = 0, worst_rot = 0;
  for (int k = 0; k < o.poses; ++k) {
    draw(rng, o, lo, hi, q, seed);
    double target[7], err[2], fk[7];
    cn_chain_fk(ch, q.data(), target);
    auto t0 = Clock::now();
    int st = cn_chain_ik(ch, target, seed.data(), o.restarts, 1e-3, 1e-2, (unsigned)k + 1,
                         sol.data(), err);
    times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    if (st < 0) {
      fprintf(stderr, "ik error: %s\n", cn_last_error());
      return 1;
    }
    double pe, re;
    cn_chain_fk(ch, sol.data(), fk);
    pose_errors(fk, target, pe, re);
    bool inside = true;
    for (int i = 0; i < nj; ++i)
      if (sol[i] < lo[i] - 1e-9 || sol[i] > hi[i] + 1e-9) inside = false;
    if (st == 0) {
      ++solved;
      worst_pos = std::max(worst_pos, pe);
      worst_rot = std::max(worst_rot, re);
      if (pe > 1e-3 || re > 1e-2) ++mismatches;
    }
    if (!inside || std::fabs(pe - err[0]) > 1e-7 || std::fabs(re - err[1]) > 1e-6) ++mismatches;
    if (k % 50 == 0) {
      double err2[2];
      int st2 = cn_chain_ik(ch, target, seed.data(), o.restarts, 1e-3, 1e-2, (unsigned)k + 1,
                            sol2.data(), err2);
      if (st2 != st || sol2 != sol) ++mismatches;
    }
  }
  report(o, "ik", tip, o.poses, solved, times, worst_pos, worst_rot, mismatches);
  cn_chain_destroy(ch);
  return mismatches ? 1 : 0;
}

// ---- the KDL peer ---------------------------------------------------------------------------

struct KdlArm {
  KDL::Chain chain;
  std::vector<double> lo, hi;
  std::vector<bool> continuous;
};

bool kdl_arm(const urdf::ModelInterface &m, const std::string &base, const std::string &tip,
             KdlArm &arm) {
  std::vector<urdf::JointConstSharedPtr> path;
  urdf::LinkConstSharedPtr l = m.getLink(tip);
  while (l && l->name != base) {
    if (!l->parent_joint) return false;
    path.push_back(l->parent_joint);
    l = m.getLink(l->parent_joint->parent_link_name);
  }
  if (!l) return false;
  std::reverse(path.begin(), path.end());
  for (auto &j : path) {
    const urdf::Pose &p = j->parent_to_joint_origin_transform;
    KDL::Frame f(KDL::Rotation::Quaternion(p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w),
                 KDL::Vector(p.position.x, p.position.y, p.position.z));
    KDL::Vector axis = f.M * KDL::Vector(j->axis.x, j->axis.y, j->axis.z);
    KDL::Joint kj(j->name, KDL::Joint::None);
    bool rot = j->type == urdf::Joint::REVOLUTE || j->type == urdf::Joint::CONTINUOUS;
    if (rot) kj = KDL::Joint(j->name, f.p, axis, KDL::Joint::RotAxis);
    if (j->type == urdf::Joint::PRISMATIC) kj = KDL::Joint(j->name, f.p, axis, KDL::Joint::TransAxis);
    arm.chain.addSegment(KDL::Segment(j->child_link_name, kj, f));
    if (kj.getType() != KDL::Joint::None) {
      bool cont = j->type == urdf::Joint::CONTINUOUS;
      arm.continuous.push_back(cont);
      arm.lo.push_back(cont ? -M_PI : j->limits->lower);
      arm.hi.push_back(cont ? M_PI : j->limits->upper);
    }
  }
  return true;
}

int run_peer(const urdf::ModelInterface &m, const std::string &tip, const Options &o) {
  KdlArm arm;
  if (!kdl_arm(m, "torso_lift_link", tip, arm)) {
    fprintf(stderr, "no chain to %s\n", tip.c_str());
    return 1;
  }
  const unsigned n = arm.chain.getNrOfJoints();
  Eigen::Matrix<double, 6, 1> L;
  L << 1, 1, 1, 0.1, 0.1, 0.1;
  KDL::ChainIkSolverPos_LMA ik(arm.chain, L, 1e-5, 100, 1e-12);
  KDL::ChainFkSolverPos_recursive fk(arm.chain);
  std::vector<double> q(n), seed(n);
  Rng rng{12345};
  std::vector<double> times;
  int solved = 0;
  for (int k = 0; k < o.peer; ++k) {
    draw(rng, o, arm.lo, arm.hi, q, seed);
    KDL::JntArray jq(n), init(n), out(n);
    for (unsigned i = 0; i < n; ++i) { jq(i) = q[i]; init(i) = seed[i]; }
    KDL::Frame goal, f;
    fk.JntToCart(jq, goal);
    std::mt19937 gen(k + 1);
    auto t0 = Clock::now();
    bool ok = false;
    for (int attempt = 0; attempt <= o.restarts && !ok; ++attempt) {
      if (attempt > 0)
        for (unsigned i = 0; i < n; ++i)
          init(i) = std::uniform_real_distribution<double>(arm.lo[i], arm.hi[i])(gen);
      ik.CartToJnt(init, goal, out);
      bool inside = true;
      for (unsigned i = 0; i < n; ++i) {
        if (arm.continuous[i]) out(i) = std::remainder(out(i), 2 * M_PI);
        else if (out(i) < arm.lo[i] || out(i) > arm.hi[i]) inside = false;
      }
      if (!inside) continue;
      fk.JntToCart(out, f);
      KDL::Vector axis;
      ok = (f.p - goal.p).Norm() <= 1e-3 && std::fabs((f.M.Inverse() * goal.M).GetRotAngle(axis)) <= 1e-2;
    }
    times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    if (ok) ++solved;
  }
  report(o, "kdl", tip, o.peer, solved, times, -1, -1, 0);
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  Options o;
  std::string search;
  auto need = [&](int i) {
    if (i + 1 >= argc) {
      fprintf(stderr, "%s needs a value\n", argv[i]);
      exit(2);
    }
    return argv[i + 1];
  };
  if (argc < 2) {
    fprintf(stderr, "usage: %s URDF [--poses N] [--restarts R] [--search-dir DIR] "
                    "[--seed random|middle] [--tip LINK]... [--peer N] [--machine]\n", argv[0]);
    return 2;
  }
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--poses") o.poses = atoi(need(i++));
    else if (a == "--restarts") o.restarts = atoi(need(i++));
    else if (a == "--search-dir") search = need(i++);
    else if (a == "--seed") o.random_seed = std::string(need(i++)) == "random";
    else if (a == "--tip") o.tips.push_back(need(i++));
    else if (a == "--peer") o.peer = atoi(need(i++));
    else if (a == "--machine") o.machine = true;
    else {
      fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (o.poses < 1) {
    fprintf(stderr, "--poses must be at least 1\n");
    return 2;
  }
  if (o.tips.empty())
    o.tips = {"l_wrist_roll_link", "r_wrist_roll_link", "l_gripper_tool_frame", "r_gripper_tool_frame"};
  std::ifstream in(argv[1]);
  std::stringstream ss;
  ss << in.rdbuf();
  if (!search.empty()) cn_add_search_dir(search.c_str());
  int w = cn_world_create(0, 0, -9.81);
  const double base[7] = {0, 0, 0, 0, 0, 0, 1};
  int r = cn_robot_add_urdf(w, ss.str().c_str(), base, 0);
  if (r < 0) {
    fprintf(stderr, "URDF %s: %s\n", argv[1], cn_last_error());
    return 1;
  }
  int bad = 0;
  for (const std::string &tip : o.tips) bad |= run_shim(w, r, tip, o);
  cn_world_destroy(w);
  if (o.peer > 0) {
    urdf::ModelInterfaceSharedPtr m = urdf::parseURDF(ss.str());
    if (!m) return 1;
    for (const std::string &tip : o.tips) bad |= run_peer(*m, tip, o);
  }
  return bad;
}

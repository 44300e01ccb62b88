// Inverse kinematics of libcram_native on random reachable poses of the PR2 arms: the tip
// pose of random joint values within the limits is solved from a seed (random within the
// limits, or the middle of the limits), and every answer is checked with the forward
// kinematics.  Usage: ik_bench URDF [POSES] [SEARCH-DIR] [RESTARTS]
// Prints one line per chain and seed mode:
//   ik CHAIN SEEDMODE solved% mean-us p99-us max-us worst-pos-m worst-rot-rad mismatches
// and exits non-zero when an answer disagrees with the forward kinematics or the result of
// a repeated call differs (determinism).
#include "cram_native.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
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

void pose_errors(const double *a, const double *b, double &pos, double &rot) {
  pos = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                  (a[2] - b[2]) * (a[2] - b[2]));
  double d = std::fabs(a[3] * b[3] + a[4] * b[4] + a[5] * b[5] + a[6] * b[6]);
  rot = 2 * std::acos(std::min(1.0, d));
}

int run(int world, int robot, const char *base, const char *tip, const char *mode, int n,
        int restarts) {
  int ch = cn_chain_create(world, robot, base, tip);
  if (ch < 0) {
    fprintf(stderr, "chain %s -> %s: %s\n", base, tip, cn_last_error());
    return 1;
  }
  int nj = cn_chain_num_joints(ch);
  std::vector<double> lo(nj), hi(nj), q(nj), seed(nj), sol(nj), sol2(nj);
  cn_chain_limits(ch, lo.data(), hi.data());
  Rng rng{12345};
  bool random_seed = std::string(mode) == "random";
  std::vector<double> times;
  int solved = 0, mismatches = 0;
  double worst_pos = 0, worst_rot = 0;
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < nj; ++i) q[i] = rng.uniform(lo[i], hi[i]);
    for (int i = 0; i < nj; ++i) seed[i] = random_seed ? rng.uniform(lo[i], hi[i]) : 0.5 * (lo[i] + hi[i]);
    double target[7], err[2], fk[7];
    cn_chain_fk(ch, q.data(), target);
    auto t0 = Clock::now();
    int st = cn_chain_ik(ch, target, seed.data(), restarts, 1e-3, 1e-2, (unsigned)k + 1,
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
      if (pe > 1e-3 || re > 1e-2 || !inside) ++mismatches;
    }
    if (std::fabs(pe - err[0]) > 1e-6 || std::fabs(re - err[1]) > 1e-6) ++mismatches;
    if (k % 50 == 0) {
      double err2[2];
      int st2 = cn_chain_ik(ch, target, seed.data(), restarts, 1e-3, 1e-2, (unsigned)k + 1,
                            sol2.data(), err2);
      if (st2 != st || sol2 != sol) ++mismatches;
    }
  }
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0;
  for (double t : times) mean += t;
  mean /= n;
  printf("ik %s->%s %s %.1f%% mean %.1f us p99 %.1f us max %.1f us worst %.2e m %.2e rad "
         "mismatches %d\n",
         base, tip, mode, 100.0 * solved / n, mean * 1e6, sorted[(size_t)(0.99 * (n - 1))] * 1e6,
         sorted.back() * 1e6, worst_pos, worst_rot, mismatches);
  cn_chain_destroy(ch);
  return mismatches ? 1 : 0;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s URDF [POSES] [SEARCH-DIR] [RESTARTS]\n", argv[0]);
    return 2;
  }
  std::ifstream in(argv[1]);
  std::stringstream ss;
  ss << in.rdbuf();
  int n = argc > 2 ? atoi(argv[2]) : 1000;
  if (argc > 3) cn_add_search_dir(argv[3]);
  int restarts = argc > 4 ? atoi(argv[4]) : 200;
  int w = cn_world_create(0, 0, -9.81);
  const double base[7] = {0, 0, 0, 0, 0, 0, 1};
  int r = cn_robot_add_urdf(w, ss.str().c_str(), base, 0);
  if (r < 0) {
    fprintf(stderr, "URDF: %s\n", cn_last_error());
    return 1;
  }
  int bad = 0;
  const char *tips[] = {"l_wrist_roll_link", "r_wrist_roll_link", "l_gripper_tool_frame",
                        "r_gripper_tool_frame"};
  for (const char *mode : {"random", "middle"})
    for (const char *tip : tips) bad |= run(w, r, "torso_lift_link", tip, mode, n, restarts);
  cn_world_destroy(w);
  return bad;
}

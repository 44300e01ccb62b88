// Self-test of the sweep checks (cn_robot_sweep_check, cn_body_sweep_check), run under
// AddressSanitizer/UBSan by `make check`.
#include "cram_native.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "cn_test.h"

// A one-metre horizontal bar turning about z at the origin, 0.5 m above the floor, and a
// second joint that lifts a 0.3 m finger at its end.
static const char *BAR =
    "<robot name='bar'><link name='base'/>"
    "<link name='bar'><collision><origin xyz='0.5 0 0'/><geometry><box size='1.0 0.04 0.04'/></geometry></collision></link>"
    "<link name='finger'><collision><origin xyz='0.15 0 0'/><geometry><box size='0.3 0.02 0.02'/></geometry></collision></link>"
    "<joint name='turn' type='revolute'><parent link='base'/><child link='bar'/><origin xyz='0 0 0.5'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "<joint name='lift' type='revolute'><parent link='bar'/><child link='finger'/><origin xyz='1.0 0 0'/><axis xyz='0 -1 0'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "</robot>";

static const double ID[7] = {0, 0, 0, 0, 0, 0, 1};

struct Rec {
  int n;
  int i4[64];
  double d4[64];
};

static Rec robot_sweep(int w, int r, const double *q0, const double *q1, const int *ign = nullptr,
                       int nign = 0, double step = 0.05, int flags = 0,
                       const double *b0 = ID, const double *b1 = ID) {
  Rec rec;
  rec.n = cn_robot_sweep_check(w, r, b0, q0, b1, q1, 2, ign, nign, step, 1e-3, flags, rec.i4,
                               rec.d4, 16);
  return rec;
}

// A two-link arm of boxes standing far from the world's origin among thin plates and boxes:
// seeded random moves against dense sampling of each link's path. Every pair that gets deeper
// than the tolerance (1 mm) somewhere is reported, no later than that place. Returns the
// number of pairs reported.
static const char *ARM =
    "<robot name='arm'><link name='base'/>"
    "<link name='upper'><collision><origin xyz='0.3 0 0'/><geometry><box size='0.6 0.05 0.05'/></geometry></collision></link>"
    "<link name='fore'><collision><origin xyz='0.2 0 0'/><geometry><box size='0.4 0.04 0.04'/></geometry></collision></link>"
    "<joint name='yaw' type='revolute'><parent link='base'/><child link='upper'/><origin xyz='0 0 0.5'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "<joint name='pitch' type='revolute'><parent link='upper'/><child link='fore'/><origin xyz='0.6 0 0'/><axis xyz='0 1 0'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "</robot>";

static int far_from_origin() {
  int w = cn_world_create(0, 0, -9.81);
  const double bx = 6.0, by = -4.0;
  double base[7] = {bx, by, 0, 0, 0, std::sin(0.3), std::cos(0.3)};
  int r = cn_robot_add_urdf(w, ARM, base, 0);
  CHECK(r == 0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<int> bodies;
  for (int i = 0; i < 8; ++i) {  // plates 6 mm thick (thinner than a sub-step's path) and boxes
    double a = M_PI * u(rng), rad = 0.55 + 0.35 * (u(rng) + 1) / 2;
    double yaw = M_PI * u(rng);
    double pose[7] = {bx + rad * std::cos(a), by + rad * std::sin(a), 0.5 + 0.25 * u(rng), 0, 0,
                      std::sin(yaw / 2), std::cos(yaw / 2)};
    bodies.push_back(i % 2 ? cn_body_add_box(w, pose, 0.006, 0.3, 0.3, 0)
                           : cn_body_add_box(w, pose, 0.08, 0.08, 0.08, 0));
  }
  int js[2] = {0, 1}, reported = 0, missed = 0, late = 0;
  const int samples = 1500;
  for (int trial = 0; trial < 40; ++trial) {
    double a[2] = {2.8 * u(rng), 1.2 * u(rng)}, c[2] = {2.8 * u(rng), 1.2 * u(rng)};
    Rec s;
    s.n = cn_robot_sweep_check(w, r, base, a, base, c, 2, nullptr, 0, 0.05, 1e-3, 0, s.i4, s.d4, 16);
    CHECK(s.n >= 0 && s.n <= 16);
    reported += s.n;
    for (int link = 1; link <= 2; ++link)
      for (int body : bodies) {
        double first_deep = -1;  // the first sampled time deeper than the tolerance
        for (int i = 0; i <= samples && first_deep < 0; ++i) {
          double t = (double)i / samples, q[2] = {a[0] + t * (c[0] - a[0]), a[1] + t * (c[1] - a[1])};
          cn_robot_set_joints(w, r, js, q, 2);
          double out7[7];
          if (cn_closest_distance(w, r, link, body, -1, 0.1, out7) == 1 && out7[0] < -1e-3) first_deep = t;
        }
        if (first_deep < 0) continue;
        int k = 0;
        while (k < s.n && !(s.i4[4 * k + 1] == link && s.i4[4 * k + 2] == body)) ++k;
        if (k == s.n)
          ++missed;
        else if (s.d4[4 * k] > first_deep + 1e-9)
          ++late;
      }
  }
  CHECK(missed == 0);
  CHECK(late == 0);
  CHECK(reported > 10);
  CHECK(cn_world_destroy(w) == 0);
  return reported;
}

// The fast search against the reference one (CN_SWEEP_REFERENCE) on seeded random scenes: a
// five-link robot (torso, arm, hand) among plates, boxes, cylinders and spheres, carrying a box
// in half of them; arm moves, torso moves, base turns and drives with the arm moving; with and
// without leaving out start contacts and ignore pairs. The records must be the same to the bit.
// Returns the number of records compared.
static const char *TORSO_ARM =
    "<robot name='torso_arm'><link name='base'><collision><origin xyz='0 0 0.15'/><geometry><box size='0.5 0.5 0.3'/></geometry></collision></link>"
    "<link name='torso'><collision><origin xyz='0 0 0.3'/><geometry><box size='0.2 0.2 0.6'/></geometry></collision></link>"
    "<link name='upper'><collision><origin xyz='0.3 0 0'/><geometry><box size='0.6 0.05 0.05'/></geometry></collision></link>"
    "<link name='fore'><collision><origin xyz='0.2 0 0'/><geometry><cylinder radius='0.03' length='0.4'/></geometry></collision></link>"
    "<link name='hand'><collision><origin xyz='0.05 0 0'/><geometry><sphere radius='0.04'/></geometry></collision></link>"
    "<joint name='lift' type='prismatic'><parent link='base'/><child link='torso'/><origin xyz='0 0 0.3'/><axis xyz='0 0 1'/><limit lower='0' upper='0.4' effort='1' velocity='1'/></joint>"
    "<joint name='yaw' type='revolute'><parent link='torso'/><child link='upper'/><origin xyz='0 0 0.5'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "<joint name='pitch' type='revolute'><parent link='upper'/><child link='fore'/><origin xyz='0.6 0 0'/><axis xyz='0 1 0'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "<joint name='roll' type='continuous'><parent link='fore'/><child link='hand'/><origin xyz='0.4 0 0'/><axis xyz='1 0 0'/></joint>"
    "</robot>";

static int fast_equals_reference() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int compared = 0, differ = 0;
  for (int scene = 0; scene < 40; ++scene) {
    int w = cn_world_create(0, 0, -9.81);
    double bx = 3 * u(rng), by = 3 * u(rng);
    double base[7] = {bx, by, 0, 0, 0, std::sin(0.3 * scene), std::cos(0.3 * scene)};
    int r = cn_robot_add_urdf(w, TORSO_ARM, base, 0);
    std::vector<int> bodies;
    for (int i = 0; i < 14; ++i) {
      double a = M_PI * u(rng), rad = 0.3 + 0.4 * (u(rng) + 1), yaw = M_PI * u(rng);
      double pose[7] = {bx + rad * std::cos(a), by + rad * std::sin(a), 0.7 + 0.4 * u(rng), 0, 0,
                        std::sin(yaw / 2), std::cos(yaw / 2)};
      int k = i % 4;
      bodies.push_back(k == 0   ? cn_body_add_box(w, pose, 0.006, 0.3, 0.3, 0)
                       : k == 1 ? cn_body_add_box(w, pose, 0.08, 0.08, 0.08, 0)
                       : k == 2 ? cn_body_add_cylinder(w, pose, 0.04, 0.3, 0)
                                : cn_body_add_sphere(w, pose, 0.05, 0));
    }
    if (scene % 2) {  // a box carried under the hand
      double lp[7];
      cn_robot_link_pose(w, r, 4, lp);
      lp[2] -= 0.08;
      int cup = cn_body_add_box(w, lp, 0.05, 0.05, 0.1, 0.2);
      cn_attach(w, cup, r, 4, 0);
    }
    int nj = cn_robot_num_joints(w, r);
    for (int move = 0; move < 20; ++move) {
      std::vector<double> q0(nj), q1(nj);
      double b0[7], b1[7];
      for (int k = 0; k < 7; ++k) b0[k] = b1[k] = base[k];
      int kind = move % 5;
      for (int j = 0; j < nj; ++j) {
        q0[j] = (kind < 2 ? 2.5 : 1.5) * u(rng);
        q1[j] = kind < 2 ? 2.5 * u(rng) : kind == 4 ? q0[j] + 0.5 * u(rng) : q0[j];
      }
      if (kind == 2) {  // the torso alone
        q0[0] = 0.2 + 0.2 * u(rng);
        q1[0] = 0.2 + 0.2 * u(rng);
      } else if (kind == 3) {  // a base turn
        double y0 = M_PI * u(rng), y1 = y0 + 2 * u(rng);
        b0[5] = std::sin(y0 / 2), b0[6] = std::cos(y0 / 2), b1[5] = std::sin(y1 / 2), b1[6] = std::cos(y1 / 2);
      } else if (kind == 4) {  // a base drive, the arm moving
        b1[0] += 0.3 * u(rng);
        b1[1] += 0.3 * u(rng);
      }
      int ign[4] = {r, 3, bodies[move % bodies.size()], -1};
      int nign = move % 3 == 1 ? 1 : 0, flags = move % 2 ? CN_SWEEP_SKIP_START_CONTACTS : 0;
      static int i4[2][4 * 128];
      static double d4[2][4 * 128];
      int n[2];
      for (int ref = 0; ref < 2; ++ref)
        n[ref] = cn_robot_sweep_check(w, r, b0, q0.data(), b1, q1.data(), nj, nign ? ign : nullptr, nign, 0.05,
                                      1e-3, flags | (ref ? CN_SWEEP_REFERENCE : 0), i4[ref], d4[ref], 128);
      if (n[0] != n[1] || n[0] < 0 || std::memcmp(i4[0], i4[1], sizeof(int) * 4 * std::min(n[0], 128)) ||
          std::memcmp(d4[0], d4[1], sizeof(double) * 4 * std::min(n[0], 128)))
        ++differ;
      compared += std::max(n[0], 0);
    }
    cn_world_destroy(w);
  }
  CHECK(differ == 0);
  CHECK(compared > 300);
  return compared;
}

int main() {
  int w = cn_world_create(0, 0, -9.81);
  int r = cn_robot_add_urdf(w, BAR, ID, 0);
  CHECK(r == 0);
  // a post (radius 5 cm) at x 0.95: the tip of the bar passes through it at angle 0, while the
  // chord between the bar's tips at -1 and +1 rad stays at x <= 0.55
  double post_pose[7] = {0.95, 0, 0.5, 0, 0, 0, 1};
  int post = cn_body_add_cylinder(w, post_pose, 0.05, 1.0, 0);
  CHECK(post == 1);
  double qa[2] = {-1, 0}, qb[2] = {1, 0};
  double poses_before[21], poses_after[21];
  CHECK(cn_robot_link_poses(w, r, poses_before, 3) == 3);

  // the arc through the post, found with one big sub-step as with many small ones
  for (double step : {2.5, 0.05, 0.01}) {
    Rec h = robot_sweep(w, r, qa, qb, nullptr, 0, step);
    CHECK(h.n == 1);
    CHECK(h.i4[0] == r && h.i4[1] == 1 && h.i4[2] == post && h.i4[3] == -1);
    // first contact: the bar's side (half width 0.02) meets the post's edge
    double expect = -std::asin(0.07 / 0.95);  // joint angle at first contact
    double frac = (expect - qa[0]) / (qb[0] - qa[0]);
    CHECK(std::fabs(h.d4[0] - frac) < 0.02);
    CHECK(std::fabs(h.d4[1] - 0.92) < 0.05 && std::fabs(h.d4[3] - 0.5) < 0.05);
  }
  // the end poses alone touch nothing
  int p4[16];
  double pd[4];
  int js[2] = {0, 1};
  CHECK(cn_robot_set_joints(w, r, js, qa, 2) == 0);
  CHECK(cn_object_contacts(w, r, 0, p4, pd, 4) == 0);
  CHECK(cn_robot_set_joints(w, r, js, qb, 2) == 0);
  CHECK(cn_object_contacts(w, r, 0, p4, pd, 4) == 0);
  double zero[2] = {0, 0};
  CHECK(cn_robot_set_joints(w, r, js, zero, 2) == 0);
  CHECK(cn_robot_link_poses(w, r, poses_after, 3) == 3);

  // the robot in the world is not moved by a sweep check
  Rec h0 = robot_sweep(w, r, qa, qb);
  double poses_now[21];
  CHECK(cn_robot_link_poses(w, r, poses_now, 3) == 3);
  CHECK(std::memcmp(poses_now, poses_after, sizeof poses_now) == 0);
  CHECK(h0.n == 1);

  // the other way round the post is not met; a turn that stops short is clear
  double qc[2] = {-1, 0}, qd[2] = {-0.2, 0};
  CHECK(robot_sweep(w, r, qc, qd).n == 0);
  double qe[2] = {1, 0}, qf[2] = {2.5, 0};
  CHECK(robot_sweep(w, r, qe, qf).n == 0);

  // with the base raised by 1.1 m the bar passes above the post (top at 1.0)
  double high[7] = {0, 0, 1.1, 0, 0, 0, 1};
  CHECK(robot_sweep(w, r, qa, qb, nullptr, 0, 0.05, 0, high, high).n == 0);

  // ignore lists: the bar against the post, the bar against anything, anything against the post
  int ign1[4] = {r, 1, post, -1}, ign2[4] = {r, 1, -1, -1}, ign3[4] = {-1, -1, post, -1};
  CHECK(robot_sweep(w, r, qa, qb, ign1, 1).n == 0);
  CHECK(robot_sweep(w, r, qa, qb, ign2, 1).n == 0);
  CHECK(robot_sweep(w, r, qa, qb, ign3, 1).n == 0);
  int ign4[4] = {r, 2, post, -1};  // the finger: the bar still hits
  CHECK(robot_sweep(w, r, qa, qb, ign4, 1).n == 1);
  // ignored pairs of the world apply too
  CHECK(cn_ignore_pair(w, r, 1, post, -1, 1) == 0);
  CHECK(robot_sweep(w, r, qa, qb).n == 0);
  CHECK(cn_ignore_pair(w, r, 1, post, -1, 0) == 0);

  // contacts at the start: reported at fraction 0, or left out with the flag
  double qs[2] = {0, 0}, qt[2] = {1.2, 0};
  Rec s0 = robot_sweep(w, r, qs, qt);
  CHECK(s0.n == 1 && s0.d4[0] == 0);
  CHECK(robot_sweep(w, r, qs, qt, nullptr, 0, 0.05, CN_SWEEP_SKIP_START_CONTACTS).n == 0);

  // a base turn with the bar out: the base turns by 2 rad about z
  double turn0[7] = {0, 0, 0, 0, 0, std::sin(-0.5), std::cos(-0.5)};
  double turn1[7] = {0, 0, 0, 0, 0, std::sin(0.5), std::cos(0.5)};
  Rec bt = robot_sweep(w, r, zero, zero, nullptr, 0, 0.05, 0, turn0, turn1);
  CHECK(bt.n == 1 && bt.i4[1] == 1 && std::fabs(bt.d4[0] - 0.5) < 0.1);
  // the base driving 2 m sideways with the bar pointing along +x sweeps the post too
  double side0[7] = {0, -1, 0, 0, 0, 0, 1}, side1[7] = {0, 1, 0, 0, 0, 0, 1};
  Rec sd = robot_sweep(w, r, zero, zero, nullptr, 0, 0.05, 0, side0, side1);
  CHECK(sd.n == 1 && std::fabs(sd.d4[0] - (1 - 0.07) / 2) < 0.01);

  // attached objects move with their link and are reported under their own handle
  double cup_pose[7] = {1.0, 0, 0.25, 0, 0, 0, 1};  // hangs under the bar's tip
  int cup = cn_body_add_box(w, cup_pose, 0.06, 0.06, 0.2, 0.3);
  CHECK(cup == 2);
  CHECK(cn_attach(w, cup, r, 1, 0) == 0);
  double low[7] = {0, 0, 0, 0, 0, 0, 1};
  double far_post[7] = {0, 1.0, 0.1, 0, 0, 0, 1};  // low: only the cup reaches down to it
  int stump = cn_body_add_box(w, far_post, 0.1, 0.1, 0.2, 0);
  double q0[2] = {0.3, 0}, q1[2] = {2.0, 0};
  Rec at = robot_sweep(w, r, q0, q1, nullptr, 0, 0.05, 0, low, low);
  bool cup_hit = false;
  for (int i = 0; i < at.n; ++i)
    if (at.i4[4 * i] == cup && at.i4[4 * i + 2] == stump) cup_hit = true;
  CHECK(cup_hit);
  {  // the paths of the finger's and the cup's frames along that move: the finger's origin is
     // the bar's tip, turning from 0.3 to 2.0 rad; the cup hangs 0.25 m under it
    int frames[6] = {r, 2, cup, -1, stump, -1};
    double path[3 * 5 * 3];
    CHECK(cn_robot_sweep_paths(w, r, low, q0, low, q1, 2, frames, 3, 4, path) == 3);
    bool ok = true;
    for (int k = 0; k <= 4; ++k) {
      double th = q0[0] + k / 4.0 * (q1[0] - q0[0]);
      const double *f = path + 3 * k, *c = path + 3 * (5 + k), *st = path + 3 * (10 + k);
      ok &= std::fabs(f[0] - std::cos(th)) < 1e-12 && std::fabs(f[1] - std::sin(th)) < 1e-12 &&
            std::fabs(f[2] - 0.5) < 1e-12;
      ok &= std::fabs(c[0] - std::cos(th)) < 1e-9 && std::fabs(c[1] - std::sin(th)) < 1e-9 &&
            std::fabs(c[2] - 0.25) < 1e-9;
      ok &= st[0] == far_post[0] && st[1] == far_post[1] && st[2] == far_post[2];  // not carried
    }
    CHECK(ok);
    int bad_link[2] = {r, 9}, bad_body[2] = {stump, 0};
    CHECK(cn_robot_sweep_paths(w, r, low, q0, low, q1, 2, bad_link, 1, 4, path) == CN_E_HANDLE &&
          strstr(cn_last_error(), "link 9"));
    CHECK(cn_robot_sweep_paths(w, r, low, q0, low, q1, 2, bad_body, 1, 4, path) == CN_E_ARG &&
          strstr(cn_last_error(), "link 0 of body"));
    CHECK(cn_robot_sweep_paths(w, r, low, q0, low, q1, 2, frames, 1, 0, path) == CN_E_ARG &&
          strstr(cn_last_error(), "steps 0"));
    CHECK(cn_robot_sweep_paths(w, r, low, q0, low, q1, 3, frames, 1, 4, path) == CN_E_ARG);
  }
  CHECK(cn_detach(w, cup, -1) == 1);
  CHECK(cn_object_remove(w, cup) == 0);

  // a plain body through a wall, and past it
  double wall_pose[7] = {3, 0, 0.5, 0, 0, 0, 1};
  int wall = cn_body_add_box(w, wall_pose, 0.02, 2, 1, 0);
  double box_pose[7] = {2, 0, 0.5, 0, 0, 0, 1};
  int box = cn_body_add_box(w, box_pose, 0.1, 0.1, 0.1, 1);
  double from[7] = {2, 0, 0.5, 0, 0, 0, 1}, to[7] = {4, 0, 0.5, 0, 0, 0, 1};
  Rec b;
  b.n = cn_body_sweep_check(w, box, from, to, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16);
  CHECK(b.n == 1 && b.i4[0] == box && b.i4[1] == -1 && b.i4[2] == wall);
  CHECK(std::fabs(b.d4[0] - (0.94 / 2)) < 0.005);  // 3 - 0.01 - 0.05 - 2 = 0.94 of 2 m
  double by[7] = {2, 3, 0.5, 0, 0, 0, 1}, by2[7] = {4, 3, 0.5, 0, 0, 0, 1};
  CHECK(cn_body_sweep_check(w, box, by, by2, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == 0);
  // capacity 0 counts only
  CHECK(cn_body_sweep_check(w, box, from, to, nullptr, 0, 0.05, 1e-3, 0, nullptr, nullptr, 0) == 1);

  // bad input: an error naming the value, never a crash
  CHECK(cn_robot_sweep_check(w, 99, ID, qa, ID, qb, 2, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_HANDLE &&
        strstr(cn_last_error(), "99"));
  CHECK(cn_robot_sweep_check(w, box, ID, qa, ID, qb, 2, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_HANDLE);
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 3, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG &&
        strstr(cn_last_error(), "3 values, expected 2"));
  double nanq[2] = {NAN, 0};
  CHECK(cn_robot_sweep_check(w, r, ID, nanq, ID, qb, 2, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG &&
        strstr(cn_last_error(), "NaN"));
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 2, nullptr, 0, 0, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG &&
        strstr(cn_last_error(), "maximum step"));
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 2, nullptr, 0, 0.05, -1, 0, b.i4, b.d4, 16) == CN_E_ARG);
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 2, nullptr, 0, 0.05, 1e-3, 8, b.i4, b.d4, 16) == CN_E_ARG &&
        strstr(cn_last_error(), "flags 8"));
  int bad_ign[4] = {r, 7, post, -1};
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 2, bad_ign, 1, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_HANDLE &&
        strstr(cn_last_error(), "link 7"));
  CHECK(cn_robot_sweep_check(w, r, ID, qa, ID, qb, 2, nullptr, 1, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG);
  double far[7] = {1e5, 0, 0, 0, 0, 0, 1};
  CHECK(cn_robot_sweep_check(w, r, ID, qa, far, qb, 2, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG &&
        strstr(cn_last_error(), "sub-steps"));
  double zq[7] = {0, 0, 0, 0, 0, 0, 0};
  CHECK(cn_body_sweep_check(w, box, zq, to, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_ARG);
  CHECK(cn_body_sweep_check(w, r, from, to, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_HANDLE);
  CHECK(cn_body_sweep_check(w, 0 + 1000, from, to, nullptr, 0, 0.05, 1e-3, 0, b.i4, b.d4, 16) == CN_E_HANDLE);
  CHECK(cn_body_sweep_check(w, box, from, to, nullptr, 0, 0.05, 1e-3, 0, nullptr, b.d4, 4) == CN_E_ARG);

  // seeded random bar moves against dense sampling of the path (2000 poses)
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.8, 2.8);
  int missed = 0, false_alarms = 0, hits = 0;
  for (int trial = 0; trial < 60; ++trial) {
    double a[2] = {u(rng), u(rng) * 0.5}, c[2] = {u(rng), u(rng) * 0.5};
    Rec s = robot_sweep(w, r, a, c);
    bool sampled = false;
    double deepest = 1;
    for (int i = 0; i <= 2000; ++i) {
      double t = i / 2000.0, q[2] = {a[0] + t * (c[0] - a[0]), a[1] + t * (c[1] - a[1])};
      cn_robot_set_joints(w, r, js, q, 2);
      double out7[7];
      for (int body : {post, wall, stump}) {
        if (cn_closest_distance(w, r, -1, body, -1, 1.0, out7) == 1) deepest = std::min(deepest, out7[0]);
      }
    }
    sampled = deepest <= 0;
    if (s.n > 0) ++hits;
    if (deepest < -2e-3 && s.n == 0) ++missed;
    if (deepest > 2e-3 && s.n > 0) ++false_alarms;
    (void)sampled;
  }
  CHECK(missed == 0);
  CHECK(false_alarms == 0);
  CHECK(hits > 5 && hits < 55);

  CHECK(cn_world_destroy(w) == 0);

  int far_hits = far_from_origin();
  int same = fast_equals_reference();
  printf("cn_sweep_check: %d checks, %d failed (random corpus: %d of 60 moves hit; far from the "
         "origin: %d pairs; %d records the same as the reference search's)\n", checks, failures, hits,
         far_hits, same);
  return failures ? 1 : 0;
}

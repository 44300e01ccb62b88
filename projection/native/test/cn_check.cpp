// Self-test of libcram_native, run under AddressSanitizer/UBSan by `make check`.
#include "cram_native.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <atomic>
#include <thread>
#include <vector>
#include <xmmintrin.h>

#include "cn_test.h"

static const char *ARM =
    "<robot name='arm'><link name='base'><collision><geometry><box size='0.2 0.2 0.1'/></geometry></collision></link>"
    "<link name='upper'><collision><origin xyz='0 0 0.25'/><geometry><cylinder radius='0.05' length='0.5'/></geometry></collision></link>"
    "<link name='tool'/>"
    "<joint name='j1' type='revolute'><parent link='base'/><child link='upper'/><origin xyz='0 0 0.05'/><axis xyz='0 0 1'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
    "<joint name='j2' type='revolute'><parent link='upper'/><child link='tool'/><origin xyz='0 0 0.5'/><axis xyz='0 1 0'/><limit lower='-2' upper='2' effort='1' velocity='1'/></joint>"
    "</robot>";

int main() {
  const double id[7] = {0, 0, 0, 0, 0, 0, 1};
  double out[64];
  int w = cn_world_create(0, 0, -9.81);
  CHECK(w >= 0);
  CHECK(cn_body_add_plane(w, 0, 0, 1, 0) == 0);
  double p0[7] = {0, 0, 2, 0, 0, 0, 1};
  int box = cn_body_add_box(w, p0, 0.2, 0.2, 0.2, 1);
  CHECK(box == 1);
  CHECK(cn_world_simulate(w, 3, 1.0 / 240) == 720);
  CHECK(cn_object_get_pose(w, box, out) == 0 && std::fabs(out[2] - 0.1) < 2e-3);

  // validation
  double bad[7] = {0, 0, NAN, 0, 0, 0, 1};
  CHECK(cn_object_set_pose(w, box, bad) == CN_E_ARG && strstr(cn_last_error(), "NaN in component 2"));
  CHECK(cn_object_set_pose(w, 77, p0) == CN_E_HANDLE && strstr(cn_last_error(), "77"));
  CHECK(cn_object_set_pose(w, box, nullptr) == CN_E_ARG);
  CHECK(cn_body_add_sphere(w, p0, -1, 1) == CN_E_ARG);
  CHECK(cn_world_step(12345, 0.01) == CN_E_HANDLE && strstr(cn_last_error(), "12345"));
  CHECK(cn_body_add_mesh(w, id, "/nonexistent/x.stl", 1, 1, 1, 0) == CN_E_FILE &&
        strstr(cn_last_error(), "/nonexistent/x.stl"));
  CHECK(cn_robot_add_urdf(w, "<robot", id, 0) == CN_E_PARSE);
  CHECK(cn_robot_add_urdf(w, nullptr, id, 0) == CN_E_ARG);

  // articulated object, joints, FK
  int r = cn_robot_add_urdf(w, ARM, id, 0);
  CHECK(r >= 0);
  CHECK(cn_robot_num_links(w, r) == 3 && cn_robot_num_joints(w, r) == 2);
  CHECK(cn_robot_link_index(w, r, "foo") == CN_E_NAME && strstr(cn_last_error(), "unknown link 'foo'"));
  int js[2] = {0, 1};
  double qs[2] = {M_PI / 2, 0};
  CHECK(cn_robot_set_joints(w, r, js, qs, 2) == 0);
  CHECK(cn_robot_link_poses(w, r, out, 3) == 3);
  CHECK(std::fabs(out[7 * 2 + 2] - 0.55) < 1e-9);
  {  // setting some joints poses only what they move, exactly as posing everything again
    double part[21], whole[21], base[7];
    int j1[1] = {1};
    double v1[1] = {0.3};
    CHECK(cn_robot_set_joints(w, r, j1, v1, 1) == 0);
    CHECK(cn_robot_link_poses(w, r, part, 3) == 3);
    CHECK(memcmp(part + 14, out + 14, 7 * sizeof(double)) != 0);  // the last link moved
    // the base pose it has leaves every link where it is; away and back poses them all again
    CHECK(cn_object_get_pose(w, r, base) == 0 && cn_object_set_pose(w, r, base) == 0);
    CHECK(cn_robot_link_poses(w, r, whole, 3) == 3);
    CHECK(memcmp(part, whole, sizeof part) == 0);
    double away[7] = {1, 2, 0, 0, 0, 0.6, 0.8}, moved[21];
    CHECK(cn_object_set_pose(w, r, away) == 0 && cn_robot_link_poses(w, r, moved, 3) == 3);
    CHECK(std::fabs(moved[0] - 1) < 1e-12 && std::fabs(moved[1] - 2) < 1e-12);
    CHECK(cn_object_set_pose(w, r, base) == 0 && cn_robot_link_poses(w, r, whole, 3) == 3);
    CHECK(memcmp(part, whole, sizeof part) == 0);
    double one = -1, all[2];
    CHECK(cn_robot_get_joint(w, r, 1, &one) == 0 && one == 0.3);
    CHECK(cn_robot_get_joints(w, r, all, 2) == 2 && all[1] == one);
    CHECK(cn_robot_get_joint(w, r, 7, &one) == CN_E_HANDLE);
    CHECK(cn_robot_set_joints(w, r, js, qs, 2) == 0);
  }
  int bad_j[1] = {9};
  CHECK(cn_robot_set_joints(w, r, bad_j, qs, 1) == CN_E_HANDLE);

  // copy, contacts, rays, attachments
  int c = cn_world_copy(w);
  CHECK(c >= 0 && cn_world_num_objects(c) == cn_world_num_objects(w));
  double far_pose[7] = {5, 5, 5, 0, 0, 0, 1};
  CHECK(cn_object_set_pose(c, box, far_pose) == 0);
  CHECK(cn_object_get_pose(w, box, out) == 0 && std::fabs(out[2] - 0.1) < 2e-3);
  int pairs[64];
  double dist[16];
  CHECK(cn_world_contacts(w, 1e-3, pairs, dist, 16) >= 1);
  CHECK(cn_object_contacts(w, box, 1e-3, pairs, dist, 16) >= 1);
  {  // leaving out the ground (object 0): none of its contacts, the others kept
    int all = cn_object_contacts(w, box, 1e-3, pairs, dist, 16);
    int ground = 0;
    for (int i = 0; i < all; ++i) ground += pairs[4 * i + 2] == 0 || pairs[4 * i] == 0;
    CHECK(ground >= 1);
    int except[1] = {0};
    int rest = cn_object_contacts_except(w, box, 1e-3, except, 1, pairs, dist, 16);
    CHECK(rest == all - ground);
    for (int i = 0; i < rest; ++i) CHECK(pairs[4 * i + 2] != 0 && pairs[4 * i] != 0);
    CHECK(cn_object_contacts_except(w, box, 1e-3, except, -1, pairs, dist, 16) == CN_E_ARG);
  }
  double from[3] = {0.5, 0.5, 3}, to[3] = {0.5, 0.5, -1};
  int hit[2];
  CHECK(cn_ray_test(w, from, to, 1, hit, out) == 1 && hit[0] == 0);
  double sp[7] = {0, 0, 0.8, 0, 0, 0, 1};
  int s = cn_body_add_sphere(w, sp, 0.05, 1);
  CHECK(cn_attach(w, s, r, 2, 0) == 0);
  qs[0] = 0;
  CHECK(cn_robot_set_joints(w, r, js, qs, 2) == 0);
  CHECK(cn_attachments(w, pairs, 4) == 1);
  CHECK(cn_detach(w, s, -1) == 1);
  CHECK(cn_object_remove(w, s) == 0);
  CHECK(cn_object_get_pose(w, s, out) == CN_E_HANDLE);

  // deferred bounding boxes: a teleported body is found at its new place by the next query, and
  // removing bodies teleported since the last query leaves nothing dangling
  {
    double a0[7] = {10, 10, 0.5, 0, 0, 0, 1}, a1[7] = {20, 20, 0.5, 0, 0, 0, 2};
    int m = cn_body_add_box(w, a0, 0.2, 0.2, 0.2, 0);
    CHECK(cn_object_set_pose(w, m, a1) == 0);  // non-unit quaternion: normalised
    CHECK(cn_object_get_pose(w, m, out) == 0 && std::fabs(out[6] - 1) < 1e-12 && out[0] == 20);
    double f[3] = {20, 20, 3}, t[3] = {20, 20, -1};
    CHECK(cn_ray_test(w, f, t, 1, hit, out) == 1 && hit[0] == m);
    double f2[3] = {10, 10, 3}, t2[3] = {10, 10, 0.3};
    CHECK(cn_ray_test(w, f2, t2, 1, hit, out) == 0);
    double zq[7] = {1, 1, 1, 0, 0, 0, 0};
    CHECK(cn_object_set_pose(w, m, zq) == CN_E_ARG && strstr(cn_last_error(), "zero quaternion"));
    double huge[7] = {1e150, 0, 0, 0, 0, 0, 1};  // outside the unmasked fast path
    CHECK(cn_object_set_pose(w, m, huge) == 0);
    CHECK(cn_object_set_pose(w, m, a0) == 0);
    CHECK(cn_object_remove(w, m) == 0);
    CHECK(cn_world_contacts(w, 1e-3, pairs, dist, 16) >= 1);
    CHECK(cn_ray_test(w, f, t, 1, hit, out) == 1 && hit[0] == 0);  // the floor, no longer m
    unsigned csr = _mm_getcsr();
    _mm_setcsr(csr & ~0x0280u);  // trap invalid and division by zero, as SBCL does
    unsigned mine = _mm_getcsr();
    CHECK(cn_world_simulate(w, 0.1, 0.01) == 10);
    CHECK(cn_object_set_pose(w, box, p0) == 0);
    CHECK((_mm_getcsr() & ~0x3Fu) == (mine & ~0x3Fu));  // control bits back; flags may differ
    _mm_setcsr(csr);
  }

  // four threads share one world and create their own: the API lock serialises them
  {
    int shared = cn_world_create(0, 0, -9.81);
    int bodies[4];
    for (int t = 0; t < 4; ++t) {
      double bp[7] = {double(t), 0, 0.5, 0, 0, 0, 1};
      bodies[t] = cn_body_add_box(shared, bp, 0.1, 0.1, 0.1, 1);
    }
    std::atomic<int> errors{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        int pr[64];
        double dd[16];
        for (int i = 0; i < 2000; ++i) {
          double q[7] = {double(t), 0.001 * (i % 7), 0.5, 0, 0, 0, 1};
          if (cn_object_set_pose(shared, bodies[t], q) != 0) ++errors;
          if (cn_object_contacts(shared, bodies[t], 0, pr, dd, 16) < 0) ++errors;
          if (i % 200 == 0) {
            int own = cn_world_create(0, 0, -9.81);
            if (own < 0 || cn_world_destroy(own) != 0) ++errors;
          }
        }
      });
    for (auto &th : threads) th.join();
    CHECK(errors == 0);
    double got[7];
    CHECK(cn_object_get_pose(shared, bodies[2], got) == 0 && got[0] == 2);
    CHECK(cn_world_destroy(shared) == 0);
  }

  // rendering and visibility
  double eye[3] = {-2, 0, 0.3}, target[3] = {0, 0, 0.3}, up[3] = {0, 0, 1}, cam[7];
  CHECK(cn_look_at(eye, target, up, CN_CAMERA_OPTICAL, cam) == 0);
  std::vector<unsigned char> rgb(64 * 48 * 3);
  std::vector<double> depth(64 * 48);
  std::vector<int> seg(64 * 48 * 2);
  CHECK(cn_render(w, cam, CN_CAMERA_OPTICAL, 50, 64, 48, 0.05, 20, rgb.data(), depth.data(), seg.data()) == 0);
  double frac;
  int occ[8];
  CHECK(cn_visibility(w, cam, CN_CAMERA_OPTICAL, 50, 64, 48, r, -1, &frac, occ, 8) >= 0 && frac > 0.5);
  {  // what lies behind the camera or wholly behind the target is not drawn, and changes nothing
    int v = cn_world_create(0, 0, -9.81);
    double at[7] = {0, 0, 0.3, 0, 0, 0, 1};
    int item = cn_body_add_box(v, at, 0.2, 0.2, 0.4, 0);
    double f0, f1, f2;
    int o0[8], o1[8], o2[8];
    CHECK(cn_visibility(v, cam, CN_CAMERA_OPTICAL, 50, 64, 48, item, -1, &f0, o0, 8) == 0 && f0 > 0.9);
    double behind_camera[7] = {-3, 0, 0.3, 0, 0, 0, 1}, behind_item[7] = {1, 0, 0.3, 0, 0, 0, 1};
    cn_body_add_box(v, behind_camera, 0.5, 4, 4, 0);
    cn_body_add_box(v, behind_item, 0.5, 4, 4, 0);
    CHECK(cn_visibility(v, cam, CN_CAMERA_OPTICAL, 50, 64, 48, item, -1, &f1, o1, 8) == 0 && f1 == f0);
    double in_front[7] = {-1, 0.1, 0.3, 0, 0, 0, 1};
    int blocker = cn_body_add_box(v, in_front, 0.1, 0.1, 0.8, 0);
    CHECK(cn_visibility(v, cam, CN_CAMERA_OPTICAL, 50, 64, 48, item, -1, &f2, o2, 8) == 1 &&
          o2[0] == blocker && f2 < f0 - 0.1);
    CHECK(cn_world_destroy(v) == 0);
  }
  CHECK(cn_render(w, cam, 7, 50, 64, 48, 0.05, 20, rgb.data(), nullptr, nullptr) == CN_E_ARG);
  CHECK(cn_write_png("/nonexistent-dir/x.png", rgb.data(), 64, 48) == CN_E_FILE);

  // IK
  int ch = cn_chain_create(w, r, "base", "tool");
  CHECK(ch >= 0 && cn_chain_num_joints(ch) == 2);
  double q[2] = {0.4, 0.3}, pose[7], sol[2], err[2], seed[2] = {0, 0};
  CHECK(cn_chain_fk(ch, q, pose) == 0);
  CHECK(cn_chain_ik(ch, pose, seed, 20, 1e-3, 1e-2, 7, sol, err) == 0 && err[0] < 1e-3);
  // the reach map: every tip position is "may reach", a point far off is not, and an IK goal
  // there is given up with the seed's error
  int ruled_out = 0;
  for (int i = 0; i < 400; ++i) {
    double qi[2] = {-3 + 6 * (i % 20) / 19.0, -3 + 6 * (i / 20) / 19.0};
    CHECK(cn_chain_fk(ch, qi, pose) == 0);
    if (cn_chain_may_reach(ch, pose, 1e-3) != 1) ++ruled_out;
  }
  CHECK(ruled_out == 0);
  double far[7] = {50, 0, 0, 0, 0, 0, 1};
  CHECK(cn_chain_may_reach(ch, far, 1e-3) == 0);
  CHECK(cn_chain_may_reach(ch, far, 1.0) == 1);  // a tolerance the map does not answer for
  CHECK(cn_chain_ik(ch, far, seed, 20, 1e-3, 1e-2, 7, sol, err) == 1 && err[0] > 40);
  double nan_pos[3] = {NAN, 0, 0};
  CHECK(cn_chain_may_reach(ch, nan_pos, 1e-3) == CN_E_ARG && strstr(cn_last_error(), "NaN"));
  CHECK(cn_chain_destroy(ch) == 0);
  CHECK(cn_chain_fk(ch, q, pose) == CN_E_HANDLE);

  // destroy; stale handles
  CHECK(cn_world_destroy(c) == 0);
  CHECK(cn_world_destroy(w) == 0);
  CHECK(cn_world_destroy(w) == CN_E_HANDLE && strstr(cn_last_error(), "is not a live world"));
  CHECK(cn_world_count() == 0);
  for (int i = 0; i < 200; ++i) {  // create/copy/destroy cycles
    int a = cn_world_create(0, 0, -9.81);
    cn_body_add_box(a, p0, 0.1, 0.1, 0.1, 1);
    cn_robot_add_urdf(a, ARM, id, 0);
    int b = cn_world_copy(a);
    cn_world_step(b, 0.01);
    cn_world_destroy(b);
    cn_world_destroy(a);
  }
  CHECK(cn_world_count() == 0);
  printf("cn_check: %d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}

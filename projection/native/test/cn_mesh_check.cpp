// Self-test of the mesh shape kinds: one convex hull per sub-mesh (compound), one hull over the
// whole mesh (CN_MESH_SINGLE_HULL, CN_URDF_SINGLE_HULL) and the exact triangle mesh.
// Run under AddressSanitizer/UBSan by `make check`.
#include "cram_native.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <unistd.h>

#include "cn_test.h"

// Two 0.2 m cubes, 0.2 m apart along x (a gap from x -0.1 to 0.1), bottoms at z 0, as two
// OBJ objects sharing one (default) material.
static void write_two_cubes(const std::string &path) {
  FILE *f = fopen(path.c_str(), "w");
  if (!f) { perror(path.c_str()); exit(2); }
  const double xs[2] = {-0.3, 0.1};
  for (int part = 0; part < 2; ++part) {
    fprintf(f, "o cube%d\n", part);
    for (int i = 0; i < 8; ++i)
      fprintf(f, "v %g %g %g\n", xs[part] + 0.2 * (i & 1), -0.1 + 0.2 * ((i >> 1) & 1),
              0.2 * ((i >> 2) & 1));
    const int faces[6][4] = {{1, 3, 4, 2}, {5, 6, 8, 7}, {1, 2, 6, 5},
                             {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}};
    for (auto &q : faces)
      fprintf(f, "f %d %d %d %d\n", q[0] + 8 * part, q[1] + 8 * part, q[2] + 8 * part,
              q[3] + 8 * part);
  }
  fclose(f);
}

// Does a 0.1 m probe cube in the middle of the gap touch object `obj`?
static bool probe_touches(int w, int obj) {
  const double at[7] = {0, 0, 0.1, 0, 0, 0, 1};
  int probe = cn_body_add_box(w, at, 0.1, 0.1, 0.1, 1);  // movable: static pairs are not checked
  int pairs[4 * 16];
  double dist[16];
  int n = cn_object_contacts(w, probe, 0, pairs, dist, 16);
  bool touches = false;
  for (int i = 0; i < n && i < 16; ++i)
    if (pairs[4 * i] == obj || pairs[4 * i + 2] == obj) touches = true;
  cn_object_remove(w, probe);
  return touches;
}

// Height at which a 0.1 m cube dropped into the gap of the mesh comes to rest on the floor or
// on the mesh (mesh bottom on the floor).
static double drop_into_gap(const char *path, double mesh_mass, int flags) {
  int w = cn_world_create(0, 0, -9.81);
  cn_body_add_plane(w, 0, 0, 1, 0);
  const double id[7] = {0, 0, 0, 0, 0, 0, 1};
  int m = cn_body_add_mesh_flags(w, id, path, 1, 1, 1, mesh_mass, flags);
  CHECK(m >= 0);
  const double above[7] = {0, 0, 0.5, 0, 0, 0, 1};
  int box = cn_body_add_box(w, above, 0.1, 0.1, 0.1, 0.1);
  cn_world_simulate(w, 2, 1.0 / 240);
  double pose[7] = {0};
  CHECK(cn_object_get_pose(w, box, pose) == 0);
  cn_world_destroy(w);
  return pose[2];
}

int main() {
  char dir_template[] = "/tmp/cn_mesh_check_XXXXXX";
  const char *dir = mkdtemp(dir_template);
  if (!dir) { perror("mkdtemp"); return 2; }
  std::string path = std::string(dir) + "/two_cubes.obj";
  write_two_cubes(path);
  const double id[7] = {0, 0, 0, 0, 0, 0, 1};
  double dims[4];

  // plain bodies; the shape cache holds each kind of shape of the file apart, so the kinds
  // alternate here
  int w = cn_world_create(0, 0, -9.81);
  int comp = cn_body_add_mesh(w, id, path.c_str(), 1, 1, 1, 1);
  CHECK(comp >= 0 && cn_body_shape(w, comp, dims) == 5);
  CHECK(!probe_touches(w, comp));  // the two cubes are two hulls: the gap stays free
  CHECK(cn_object_remove(w, comp) == 0);
  int one = cn_body_add_mesh_flags(w, id, path.c_str(), 1, 1, 1, 1, CN_MESH_SINGLE_HULL);
  CHECK(one >= 0 && cn_body_shape(w, one, dims) == 5 && dims[0] == 1);
  CHECK(probe_touches(w, one));    // one hull around both cubes fills the gap
  CHECK(cn_object_remove(w, one) == 0);
  int again = cn_body_add_mesh_flags(w, id, path.c_str(), 1, 1, 1, 1, 0);
  CHECK(again >= 0 && !probe_touches(w, again));
  CHECK(cn_object_remove(w, again) == 0);
  // static: the exact mesh, or the one hull when asked for
  int exact = cn_body_add_mesh(w, id, path.c_str(), 1, 1, 1, 0);
  CHECK(exact >= 0 && !probe_touches(w, exact));
  CHECK(cn_object_remove(w, exact) == 0);
  int static_one = cn_body_add_mesh_flags(w, id, path.c_str(), 1, 1, 1, 0, CN_MESH_SINGLE_HULL);
  CHECK(static_one >= 0 && probe_touches(w, static_one));
  double box[6];
  CHECK(cn_object_aabb(w, static_one, -1, box) == 0 && std::fabs(box[0] + 0.3) < 5e-3 &&
        std::fabs(box[3] - 0.3) < 5e-3 && std::fabs(box[5] - 0.2) < 5e-3);
  // the hull keeps every corner: its underside is flat at z 0 (less the margin) all over
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 2; ++j) {
      double x = -0.29 + 0.145 * i, y = j ? 0.09 : -0.09;
      double from[3] = {x, y, -1}, to[3] = {x, y, 1}, hit7[7];
      int hit[2];
      CHECK(cn_ray_test(w, from, to, 1, hit, hit7) == 1 && hit[0] == static_one &&
            std::fabs(hit7[3] + 0.001) < 5e-4);
    }
  CHECK(cn_object_remove(w, static_one) == 0);
  // bad flags name themselves
  CHECK(cn_body_add_mesh_flags(w, id, path.c_str(), 1, 1, 1, 1, 6) == CN_E_ARG &&
        strstr(cn_last_error(), "mesh flags 6"));
  CHECK(cn_body_add_mesh_flags(w, id, "/nonexistent/y.obj", 1, 1, 1, 1, CN_MESH_SINGLE_HULL) ==
            CN_E_FILE && strstr(cn_last_error(), "/nonexistent/y.obj"));

  // URDF links: the same mesh as one hull per sub-mesh or as one hull; the parsed-model cache
  // keeps the two apart for the same text
  std::string urdf = "<robot name='m'><link name='a'><collision><geometry><mesh filename='" +
                     path + "'/></geometry></collision></link></robot>";
  int r0 = cn_robot_add_urdf(w, urdf.c_str(), id, 0);
  CHECK(r0 >= 0 && !probe_touches(w, r0));
  CHECK(cn_object_remove(w, r0) == 0);
  int r1 = cn_robot_add_urdf(w, urdf.c_str(), id, CN_URDF_SINGLE_HULL);
  CHECK(r1 >= 0 && probe_touches(w, r1));
  CHECK(cn_object_remove(w, r1) == 0);
  int r2 = cn_robot_add_urdf(w, urdf.c_str(), id, CN_URDF_EXACT_MESHES);
  CHECK(r2 >= 0 && !probe_touches(w, r2));
  CHECK(cn_object_remove(w, r2) == 0);
  CHECK(cn_robot_add_urdf(w, urdf.c_str(), id, CN_URDF_EXACT_MESHES | CN_URDF_SINGLE_HULL) ==
            CN_E_ARG && strstr(cn_last_error(), "exclude each other"));
  CHECK(cn_robot_add_urdf(w, urdf.c_str(), id, 4) == CN_E_ARG &&
        strstr(cn_last_error(), "unknown URDF flags 4"));
  CHECK(cn_world_destroy(w) == 0);

  // physics: a cube dropped into the gap reaches the floor between the parts (z 0.05), and
  // lands on top of the one hull (z 0.25)
  double z = drop_into_gap(path.c_str(), 1, 0);
  CHECK(std::fabs(z - 0.05) < 5e-3);
  z = drop_into_gap(path.c_str(), 1, CN_MESH_SINGLE_HULL);
  CHECK(std::fabs(z - 0.25) < 5e-3);
  z = drop_into_gap(path.c_str(), 0, 0);
  CHECK(std::fabs(z - 0.05) < 5e-3);
  z = drop_into_gap(path.c_str(), 0, CN_MESH_SINGLE_HULL);
  CHECK(std::fabs(z - 0.25) < 5e-3);

  CHECK(cn_world_count() == 0);
  unlink(path.c_str());
  rmdir(dir);
  printf("cn_mesh_check: %d checks, %d failures\n", checks, failures);
  return failures ? 1 : 0;
}

// Plain bodies: adding planes, boxes, spheres, cylinders, cones, meshes and convex hulls, and
// their velocity, mass and shape.
#include "cn_internal.hpp"

using namespace cn;

extern "C" {

int cn_body_add_plane(int wh, double nx, double ny, double nz, double c) {
  return guard([&] {
    world(wh);
    btVector3 n(check_finite(nx, "normal x"), check_finite(ny, "normal y"),
                check_finite(nz, "normal z"));
    check_finite(c, "plane constant");
    if (n.length() < 1e-9) fail(CN_E_ARG, "plane normal (%g %g %g) has zero length", nx, ny, nz);
    static const double id[7] = {0, 0, 0, 0, 0, 0, 1};
    return add_body(wh, id, make_plane(n.normalized(), c), 0, "plane");
  });
}

int cn_body_add_box(int wh, const double *pose, double sx, double sy, double sz, double mass) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    check_positive(sx, "box size x");
    check_positive(sy, "box size y");
    check_positive(sz, "box size z");
    check_nonneg(mass, "mass");
    return add_body(wh, pose, make_box(sx, sy, sz), mass, "box");
  });
}

int cn_body_add_sphere(int wh, const double *pose, double r, double mass) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    check_positive(r, "sphere radius");
    check_nonneg(mass, "mass");
    return add_body(wh, pose, make_sphere(r), mass, "sphere");
  });
}

int cn_body_add_cylinder(int wh, const double *pose, double r, double h, double mass) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    check_positive(r, "cylinder radius");
    check_positive(h, "cylinder height");
    check_nonneg(mass, "mass");
    return add_body(wh, pose, make_cylinder(r, h), mass, "cylinder");
  });
}

int cn_body_add_cone(int wh, const double *pose, double r, double h, double mass) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    check_positive(r, "cone radius");
    check_positive(h, "cone height");
    check_nonneg(mass, "mass");
    return add_body(wh, pose, make_cone(r, h), mass, "cone");
  });
}

int cn_body_add_mesh_flags(int wh, const double *pose, const char *path, double sx, double sy,
                           double sz, double mass, int flags) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    if (flags & ~CN_MESH_SINGLE_HULL)
      fail(CN_E_ARG, "unknown mesh flags %d (known: CN_MESH_SINGLE_HULL = %d)", flags,
           CN_MESH_SINGLE_HULL);
    std::string p = resolve_path(check_str(path, "mesh path"), "");
    btVector3 s(check_positive(sx, "mesh scale x"), check_positive(sy, "mesh scale y"),
                check_positive(sz, "mesh scale z"));
    check_nonneg(mass, "mass");
    MeshMode mode = (flags & CN_MESH_SINGLE_HULL) ? MeshMode::OneHull
                    : mass == 0                   ? MeshMode::Exact
                                                  : MeshMode::Hulls;
    return add_body(wh, pose, load_mesh(p, s, mode), mass, "mesh");
  });
}

int cn_body_add_mesh(int wh, const double *pose, const char *path, double sx, double sy,
                     double sz, double mass) {
  return cn_body_add_mesh_flags(wh, pose, path, sx, sy, sz, mass, 0);
}

int cn_body_add_convex_hull(int wh, const double *pose, const double *pts, int n, double mass) {
  return guard([&] {
    world(wh);
    read_pose(pose);
    if (n < 4) fail(CN_E_ARG, "convex hull needs at least 4 points, got %d", n);
    check_ptr(pts, "point array");
    check_nonneg(mass, "mass");
    return add_body(wh, pose, make_hull(pts, n), mass, "hull");
  });
}

int cn_body_get_velocity(int wh, int bh, double *out) {
  return guard([&] {
    Object &o = world(wh).body(bh);
    check_ptr(out, "velocity output");
    btVector3 l = o.rb->getLinearVelocity(), a = o.rb->getAngularVelocity();
    for (int i = 0; i < 3; ++i) { out[i] = l[i]; out[3 + i] = a[i]; }
    return 0;
  });
}

int cn_body_set_velocity(int wh, int bh, const double *v) {
  return guard([&] {
    Object &o = world(wh).body(bh);
    check_ptr(v, "velocity");
    for (int i = 0; i < 6; ++i)
      if (!std::isfinite(v[i]))
        fail(CN_E_ARG, "velocity has %s in component %d", std::isnan(v[i]) ? "NaN" : "an infinity", i);
    if (o.rb->isStaticOrKinematicObject()) return 0;
    o.rb->setLinearVelocity(btVector3(v[0], v[1], v[2]));
    o.rb->setAngularVelocity(btVector3(v[3], v[4], v[5]));
    o.rb->activate(true);
    return 0;
  });
}

int cn_body_get_mass(int wh, int bh, double *out) {
  return guard([&] {
    Object &o = world(wh).body(bh);
    check_ptr(out, "mass output");
    *out = o.mass;
    return 0;
  });
}

int cn_body_shape(int wh, int bh, double *out) {
  return guard([&] {
    Object &o = world(wh).body(bh);
    check_ptr(out, "shape output");
    for (int i = 0; i < 4; ++i) out[i] = o.shape->dims[i];
    return o.shape->kind;
  });
}

}  // extern "C"

// Visibility queries (cn_visibility, cn_visibility_above): how much of an object a camera sees.
//
// The query counts pixels of the object in three small segmentation images: the object alone
// from the camera, the whole scene inside the object's rectangle, and the object alone with the
// camera turned towards it. They are drawn here by a rasterizer of object ids and depths in the
// calling thread, with OpenGL's conventions (perspective frustum, pixel centres, depth test
// LESS, back faces culled, a user clip plane): the same pictures as cn_render's segmentation
// image up to pixels on an edge. A software GL pipeline sets up each frame at a cost of several
// times the rasterizing itself, the more so between a plan's other work, which leaves its
// caches cold. No lock: each thread draws into images of its own.
#include "cn_internal.hpp"

#include <algorithm>

namespace cn {
namespace {

// A vertex in clip coordinates, with its signed distance to the user clip plane.
struct ClipVertex {
  double x, y, z, w, plane;
};

struct SegImage {
  int w = 0, h = 0;
  std::vector<float> depth;  // window depth (NDC z), +inf = nothing
  std::vector<int> obj, link;
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // the rectangle of the pixels drawn since the last clear
  size_t covered = 0;                     // how many pixels were drawn since the last clear
  // Nothing drawn: the whole image after a change of size, else only the rectangle drawn.
  void clear(int width, int height) {
    if (width != w || height != h) {
      w = width;
      h = height;
      const size_t n = (size_t)w * h;
      depth.assign(n, INFINITY);
      obj.assign(n, -1);
      link.assign(n, -1);
    } else {
      for (int y = y0; y <= y1; ++y) {
        const size_t a = (size_t)y * w + x0, b = (size_t)y * w + x1 + 1;
        std::fill(depth.begin() + a, depth.begin() + b, INFINITY);
        std::fill(obj.begin() + a, obj.begin() + b, -1);
        std::fill(link.begin() + a, link.begin() + b, -1);
      }
    }
    x0 = w;
    y0 = h;
    x1 = y1 = -1;
    covered = 0;
  }
  void put(size_t i, int x, int y, float z, int o, int l) {
    if (depth[i] == INFINITY) {
      ++covered;
      x0 = std::min(x0, x); x1 = std::max(x1, x);
      y0 = std::min(y0, y); y1 = std::max(y1, y);
    }
    depth[i] = z;
    obj[i] = o;
    link[i] = l;
  }
};

// What one image is drawn with: the camera, the pixel rectangle drawn into (inclusive), and
// the object whose parts below a height are clipped away (-1: none).
struct Raster {
  btTransform view;  // OpenGL camera frame <- world
  double sx = 0, sy = 0, a = 0, b = 0;  // projection: x_c = sx x_e, y_c = sy y_e, z_c = a z_e + b
  double near_m = 0;
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  int clip_obj = -1;
  double clip_z = -INFINITY;
  double far_cut = INFINITY;  // items wholly farther than this (eye depth) are not drawn
  bool cull_items = false;    // skip items whose bounding box projects outside the rectangle
};

Raster make_raster(const Camera &cam) {
  Raster r;
  r.view = gl_camera(cam).inverse();
  double right, top;
  frustum_half_extents(cam, right, top);
  r.sx = cam.near_m / right;
  r.sy = cam.near_m / top;
  r.a = -(cam.far_m + cam.near_m) / (cam.far_m - cam.near_m);
  r.b = -2.0 * cam.far_m * cam.near_m / (cam.far_m - cam.near_m);
  r.near_m = cam.near_m;
  r.x0 = 0;
  r.y0 = 0;
  r.x1 = cam.w - 1;
  r.y1 = cam.h - 1;
  return r;
}

// Whether an item (mesh bounds under world <- item transform T with SCALE) can leave a pixel in
// the raster's rectangle: the projection of its bounding box, widened by two pixels.
bool item_may_show(const Raster &r, const RenderMesh &m, const btTransform &t, const btVector3 &scale,
                   int w, int h) {
  btVector3 lo, hi;
  m.bounds(lo, hi);
  const btTransform e = r.view * t;
  double px0 = 1e300, py0 = 1e300, px1 = -1e300, py1 = -1e300, nearest = INFINITY;
  int behind = 0;
  for (int k = 0; k < 8; ++k) {
    btVector3 corner((k & 1 ? hi : lo).x() * scale.x(), (k & 2 ? hi : lo).y() * scale.y(),
                     (k & 4 ? hi : lo).z() * scale.z());
    btVector3 pc = e * corner;
    nearest = std::min(nearest, -pc.z());
    if (pc.z() > -r.near_m) {
      ++behind;
      continue;
    }
    double x = (pc.x() * r.sx / -pc.z() + 1) * 0.5 * w;
    double y = (pc.y() * r.sy / -pc.z() + 1) * 0.5 * h;
    px0 = std::min(px0, x); px1 = std::max(px1, x);
    py0 = std::min(py0, y); py1 = std::max(py1, y);
  }
  if (behind == 8) return false;
  if (nearest > r.far_cut) return false;
  if (behind > 0) return true;
  return !(px1 < r.x0 - 1 || px0 > r.x1 + 2 || py1 < r.y0 - 1 || py0 > r.y1 + 2);
}

// Clip polygon IN (n vertices) against the half space where DIST >= 0; -> vertices in OUT.
template <class Dist>
int clip_polygon(const ClipVertex *in, int n, ClipVertex *out, Dist dist) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const ClipVertex &p = in[i], &q = in[(i + 1) % n];
    const double dp = dist(p), dq = dist(q);
    if (dp >= 0) out[m++] = p;
    if ((dp >= 0) != (dq >= 0)) {
      const double t = dp / (dp - dq);
      out[m++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z),
                  p.w + t * (q.w - p.w), p.plane + t * (q.plane - p.plane)};
    }
  }
  return m;
}

struct WinVertex {
  double x, y, z;
};

// Fill the triangle a b c (window coordinates, counter-clockwise) into IMG with (obj, link)
// where it is nearer than what is there; pixel centres inside or on a top or left edge.
void fill_triangle(SegImage &img, const Raster &r, const WinVertex &a, const WinVertex &b,
                   const WinVertex &c, double area, int obj, int link) {
  const int xa = std::max(r.x0, (int)std::floor(std::min({a.x, b.x, c.x}) - 0.5));
  const int xb = std::min(r.x1, (int)std::ceil(std::max({a.x, b.x, c.x}) - 0.5));
  const int ya = std::max(r.y0, (int)std::floor(std::min({a.y, b.y, c.y}) - 0.5));
  const int yb = std::min(r.y1, (int)std::ceil(std::max({a.y, b.y, c.y}) - 0.5));
  if (xa > xb || ya > yb) return;
  // edge functions: e(p) = (q - o) x (p - o), >= 0 inside a counter-clockwise triangle
  struct Edge {
    double dx, dy, ox, oy;
    bool top_left;
    double at(double px, double py) const { return dx * (py - oy) - dy * (px - ox); }
    bool inside(double e) const { return e > 0 || (e == 0 && top_left); }
  };
  auto edge = [](const WinVertex &o, const WinVertex &q) {
    const double dx = q.x - o.x, dy = q.y - o.y;
    return Edge{dx, dy, o.x, o.y, dy < 0 || (dy == 0 && dx < 0)};
  };
  const Edge e0 = edge(b, c), e1 = edge(c, a), e2 = edge(a, b);  // e0 weighs a, e1 b, e2 c
  const double inv = 1.0 / area;
  for (int y = ya; y <= yb; ++y) {
    const double py = y + 0.5;
    double w0 = e0.at(xa + 0.5, py), w1 = e1.at(xa + 0.5, py), w2 = e2.at(xa + 0.5, py);
    const size_t row = (size_t)y * img.w;
    for (int x = xa; x <= xb; ++x, w0 -= e0.dy, w1 -= e1.dy, w2 -= e2.dy) {
      if (!(e0.inside(w0) && e1.inside(w1) && e2.inside(w2))) continue;
      const float z = (float)((w0 * a.z + w1 * b.z + w2 * c.z) * inv);
      const size_t i = row + x;
      if (z < img.depth[i]) img.put(i, x, y, z, obj, link);
    }
  }
}

// Fill the polygon WIN (n window vertices, counter-clockwise when front facing) as a fan.
void fill_polygon(SegImage &img, const Raster &r, const WinVertex *win, int n, int obj, int link) {
  double area = 0;  // twice the signed area: > 0 counter-clockwise (front facing)
  for (int k = 0; k < n; ++k) {
    const WinVertex &s = win[k], &q = win[(k + 1) % n];
    area += s.x * q.y - q.x * s.y;
  }
  if (!(area > 0)) return;  // back facing or degenerate
  for (int k = 1; k + 1 < n; ++k) {
    const WinVertex &a = win[0], &b = win[k], &c = win[k + 1];
    const double tri = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (tri > 0) fill_triangle(img, r, a, b, c, tri, obj, link);
  }
}

inline WinVertex to_window(const ClipVertex &c, int w, int h) {
  const double iw = 1.0 / c.w;
  return {(c.x * iw + 1) * 0.5 * w, (c.y * iw + 1) * 0.5 * h, c.z * iw};
}

// The raster's rectangle in normalised device coordinates, widened by a pixel: x left, x right,
// y bottom, y top.
struct NdcRect {
  double xl, xr, yl, yr;
};

NdcRect ndc_rect(const Raster &r, int w, int h) {
  return {2.0 * (r.x0 - 1) / w - 1, 2.0 * (r.x1 + 2) / w - 1, 2.0 * (r.y0 - 1) / h - 1,
          2.0 * (r.y1 + 2) / h - 1};
}

// Draw the items (world <- frame) of (obj, link) into IMG, the raster's rectangle being NDC.
void draw_items(SegImage &img, const Raster &r, const NdcRect &ndc,
                const std::vector<RenderItem> &items, const btTransform &frame, int obj, int link) {
  const bool clip = obj == r.clip_obj;
  for (const RenderItem &it : items) {
    const btTransform t = frame * it.local;
    if (r.cull_items && !item_may_show(r, *it.mesh, t, it.scale, img.w, img.h)) continue;
    // clip coordinates and the clip plane's distance as affine functions of the mesh's
    // coordinates: rows x y z w of the projection of the camera frame, and world z - clip z
    const btTransform e = r.view * t;
    double m[5][4];
    const double scale[3] = {it.scale.x(), it.scale.y(), it.scale.z()};
    const double rows[3] = {r.sx, r.sy, 1.0};
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) m[row][col] = e.getBasis()[row][col] * scale[col] * rows[row];
      m[row][3] = e.getOrigin()[row] * rows[row];
    }
    for (int col = 0; col < 4; ++col) {  // z_c = a z_e + b, w_c = -z_e
      const double ze = m[2][col];
      m[2][col] = r.a * ze + (col == 3 ? r.b : 0.0);
      m[3][col] = -ze;
    }
    for (int col = 0; col < 3; ++col) m[4][col] = t.getBasis()[2][col] * scale[col];
    m[4][3] = t.getOrigin().z() - r.clip_z;
    const double xl = ndc.xl, xr = ndc.xr, yl = ndc.yl, yr = ndc.yr;
    const std::vector<float> &p = it.mesh->pos;
    for (size_t i = 0; i + 8 < p.size(); i += 9) {
      ClipVertex v[3];
      int outside_all = 0x7f, outside_any = 0;
      for (int k = 0; k < 3; ++k) {
        const double x = p[i + 3 * k], y = p[i + 3 * k + 1], z = p[i + 3 * k + 2];
        ClipVertex &c = v[k];
        c.x = m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3];
        c.y = m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3];
        c.z = m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3];
        c.w = m[3][0] * x + m[3][1] * y + m[3][2] * z + m[3][3];
        c.plane = clip ? m[4][0] * x + m[4][1] * y + m[4][2] * z + m[4][3] : 0.0;
        const int code = (c.x > xr * c.w) | (c.x < xl * c.w) << 1 | (c.y > yr * c.w) << 2 | (c.y < yl * c.w) << 3 |
                         (c.z > c.w) << 4 | (c.z < -c.w) << 5 | (c.plane < 0) << 6;
        outside_all &= code;
        outside_any |= code;
      }
      if (outside_all) continue;  // wholly beyond one plane or beside the rectangle
      if (!(outside_any & 0x70)) {  // in front of the near plane, before the far one, above the cut
        const WinVertex win[3] = {to_window(v[0], img.w, img.h), to_window(v[1], img.w, img.h),
                                  to_window(v[2], img.w, img.h)};
        fill_polygon(img, r, win, 3, obj, link);
        continue;
      }
      ClipVertex buf_a[9], buf_b[9];
      int n = clip_polygon(v, 3, buf_a, [](const ClipVertex &c) { return c.z + c.w; });  // near
      n = clip_polygon(buf_a, n, buf_b, [](const ClipVertex &c) { return c.w - c.z; });  // far
      const ClipVertex *poly = buf_b;
      if (clip && n > 0) {
        n = clip_polygon(buf_b, n, buf_a, [](const ClipVertex &c) { return c.plane; });
        poly = buf_a;
      }
      if (n < 3) continue;
      WinVertex win[9];
      for (int k = 0; k < n; ++k) win[k] = to_window(poly[k], img.w, img.h);
      fill_polygon(img, r, win, n, obj, link);
    }
  }
}

// Draw the world's objects (only_obj >= 0: that one, only_link >= 0: that link of it).
void draw_world(SegImage &img, const Raster &r, World &w, int only_obj, int only_link) {
  const NdcRect ndc = ndc_rect(r, img.w, img.h);
  for (Object *o : w.objects) {
    if (!o || (only_obj >= 0 && o->id != only_obj)) continue;
    if (o->kind == CN_BODY) {
      if (o->shape) draw_items(img, r, ndc, o->shape->draw, o->rb->getWorldTransform(), o->id, -1);
    } else {
      const Model &m = *o->model;
      for (size_t l = 0; l < m.links.size(); ++l) {
        if (only_link >= 0 && (int)l != only_link) continue;
        draw_items(img, r, ndc, m.links[l].visual, o->link_pose[l], o->id, (int)l);
      }
    }
  }
}

}  // namespace
}  // namespace cn

using namespace cn;

extern "C" {

int cn_visibility(int wh, const double *cam7, int convention, double fov, int width, int height,
                  int oh, int link, double *out_fraction, int *occ, int cap) {
  return cn_visibility_above(wh, cam7, convention, fov, width, height, oh, link, -INFINITY,
                             out_fraction, occ, cap);
}

int cn_visibility_above(int wh, const double *cam7, int convention, double fov, int width,
                        int height, int oh, int link, double min_z, double *out_fraction, int *occ,
                        int cap) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.obj(oh, "target object");
    if (o.kind == CN_BODY && link != -1) fail(CN_E_HANDLE, "link %d given for body %d, expected -1", link, oh);
    if (o.kind == CN_ARTICULATED && (link < -1 || link >= (int)o.link_rb.size()))
      fail(CN_E_HANDLE, "link index %d out of range -1..%d in articulated object %d", link,
           (int)o.link_rb.size() - 1, oh);
    check_ptr(out_fraction, "fraction output");
    check_output(cap, occ, "occluder output");
    if (std::isnan(min_z) || min_z == INFINITY)
      fail(CN_E_ARG, "min_z is %g, expected a height in metres or -inf", min_z);
    Camera cam = read_camera(cam7, convention, fov, width, height, 0.05, 50.0);
    static thread_local SegImage tls_alone, tls_scene;
    SegImage &alone = tls_alone, &scene = tls_scene;
    Raster r = make_raster(cam);
    if (std::isfinite(min_z)) {
      r.clip_obj = oh;
      r.clip_z = min_z;
    }
    // 1. the target alone from the real camera: its pixels and their rectangle (each pixel
    // drawn in these images is one of the target's)
    alone.clear(width, height);
    draw_world(alone, r, w, oh, link);
    const size_t in_view = alone.covered;
    if (in_view == 0) {  // not in the picture at all: nothing of it is visible
      *out_fraction = 0.0;
      return 0;
    }
    // the target's bounding box: its farthest depth (2) and its centre (3)
    btVector3 lo, hi;
    const bool any = union_aabb(o, link, lo, hi);
    // 2. the whole scene, drawn only where the target is: occluders cover its pixels
    size_t visible = 0;
    std::set<int> occluders;
    {
      Raster s = r;
      s.x0 = alone.x0; s.y0 = alone.y0; s.x1 = alone.x1; s.y1 = alone.y1;
      s.cull_items = true;
      if (any) {  // a corner of the box is the farthest point
        double far = 0;
        for (int k = 0; k < 8; ++k) {
          btVector3 corner(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                           k & 4 ? hi.z() : lo.z());
          far = std::max(far, -(s.view * corner).z());
        }
        s.far_cut = far;
      }
      scene.clear(width, height);
      draw_world(scene, s, w, -1, -1);
      for (int y = s.y0; y <= s.y1; ++y)
        for (size_t i = (size_t)y * width + s.x0, end = (size_t)y * width + s.x1; i <= end; ++i)
          if (alone.obj[i] >= 0) {
            const int hit = scene.obj[i];
            if (hit == oh && (link < 0 || scene.link[i] == link)) ++visible;
            else if (hit >= 0 && hit != oh) occluders.insert(hit);
          }
    }
    // 3. the target alone with the camera turned towards it
    btVector3 center = any ? (lo + hi) * 0.5 : frame_pose(o, link).getOrigin();
    size_t total = in_view;
    btVector3 eye = cam.pose.getOrigin();
    if ((center - eye).length() > 1e-6) {
      Camera facing = cam;
      btVector3 up = cam.convention == CN_CAMERA_OPTICAL ? -(cam.pose.getBasis().getColumn(1))
                                                         : cam.pose.getBasis().getColumn(2);
      facing.pose = look_at_tf(eye, center, up, cam.convention);
      Raster f = make_raster(facing);
      f.clip_obj = r.clip_obj;
      f.clip_z = r.clip_z;
      scene.clear(width, height);
      draw_world(scene, f, w, oh, link);
      total = std::max(scene.covered, in_view);
    }
    *out_fraction = total ? std::min(1.0, (double)visible / (double)total) : 0.0;
    int n = 0;
    for (int ob : occluders) {
      if (n < cap) occ[n] = ob;
      ++n;
    }
    return n;
  });
}

}  // extern "C"

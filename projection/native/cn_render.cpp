// Headless rendering with OSMesa: colour, depth and segmentation images, PNG (the visibility
// queries draw their own small segmentation images: cn_visibility.cpp).
#include "cn_internal.hpp"

#include <GL/gl.h>
#include <GL/osmesa.h>
#include <png.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace cn {

namespace {

// llvmpipe (Mesa's software rasterizer behind OSMesa) hands every render to worker threads and
// waits for them at a barrier. The renders here are small (a robot camera's picture): waking
// the workers and waiting for them cost more than rasterizing in the calling thread, which
// gives the same pixels. Set when the library is loaded, before the first context; a user's
// own LP_NUM_THREADS is kept.
__attribute__((constructor)) void rasterize_in_calling_thread() {
  setenv("LP_NUM_THREADS", "0", 0);
}

struct GLContext {
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> buf;
  int w = 0, h = 0;
  std::unordered_map<uint64_t, GLuint> lists;
  ~GLContext() {
    if (ctx) OSMesaDestroyContext(ctx);
  }
};
// One context for the process, shared by every thread that renders (plans run in threads of
// their own): its compiled shaders and display lists outlive the threads. GL_MUTEX serialises
// its use; the caller holds it for a whole render.
std::unique_ptr<GLContext> g_gl;
std::recursive_mutex &gl_mutex() {
  static std::recursive_mutex m;
  return m;
}

// Display lists of meshes that no longer exist, deleted at the next render. Never destroyed:
// meshes held by static objects of other files may go after this file's statics.
std::mutex &g_dead_mutex = *new std::mutex;
std::vector<uint64_t> &g_dead_meshes = *new std::vector<uint64_t>;

void delete_dead_lists(GLContext &c) {
  std::vector<uint64_t> dead;
  {
    std::lock_guard<std::mutex> lock(g_dead_mutex);
    dead.swap(g_dead_meshes);
  }
  for (uint64_t id : dead) {
    auto it = c.lists.find(id);
    if (it != c.lists.end()) {
      glDeleteLists(it->second, 1);
      c.lists.erase(it);
    }
  }
}

GLContext &gl_context(int w, int h) {
  if (!g_gl) {
    auto c = std::make_unique<GLContext>();
    c->ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (!c->ctx) fail(CN_E_RENDER, "OSMesaCreateContextExt failed (no software renderer?)");
    g_gl = std::move(c);
  }
  GLContext &c = *g_gl;
  if (c.w != w || c.h != h || OSMesaGetCurrentContext() != c.ctx) {
    if ((size_t)w * h * 4 > c.buf.size()) c.buf.resize((size_t)w * h * 4);
    if (!OSMesaMakeCurrent(c.ctx, c.buf.data(), GL_UNSIGNED_BYTE, w, h))
      fail(CN_E_RENDER, "OSMesaMakeCurrent failed for a %dx%d image", w, h);
    c.w = w;
    c.h = h;
  }
  delete_dead_lists(c);
  return c;
}

}  // namespace

void forget_render_mesh(uint64_t id) {
  std::lock_guard<std::mutex> lock(g_dead_mutex);
  g_dead_meshes.push_back(id);
}

namespace {

GLuint mesh_list(GLContext &c, const RenderMesh &m) {
  auto it = c.lists.find(m.id);
  if (it != c.lists.end()) return it->second;
  GLuint l = glGenLists(1);
  glNewList(l, GL_COMPILE);
  glBegin(GL_TRIANGLES);
  for (size_t i = 0; i + 2 < m.pos.size(); i += 3) {
    glNormal3f(m.nrm[i], m.nrm[i + 1], m.nrm[i + 2]);
    glVertex3f(m.pos[i], m.pos[i + 1], m.pos[i + 2]);
  }
  glEnd();
  glEndList();
  c.lists[m.id] = l;
  return l;
}

void setup_camera(const Camera &cam) {
  glViewport(0, 0, cam.w, cam.h);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  double right, top;
  frustum_half_extents(cam, right, top);
  glFrustum(-right, right, -top, top, cam.near_m, cam.far_m);
  glMatrixMode(GL_MODELVIEW);
  double m[16];
  gl_camera(cam).inverse().getOpenGLMatrix(m);
  glLoadMatrixd(m);
}

enum Mode { COLOR, SEG };

void draw_items(GLContext &c, const std::vector<RenderItem> &items, const btTransform &frame,
                Mode mode, const float *override_rgba) {
  for (const RenderItem &it : items) {
    if (mode == COLOR) {
      const float *col = override_rgba ? override_rgba : it.rgba;
      glColor4f(col[0], col[1], col[2], 1.0f);
    }
    double m[16];
    (frame * it.local).getOpenGLMatrix(m);
    glPushMatrix();
    glMultMatrixd(m);
    glScaled(it.scale.x(), it.scale.y(), it.scale.z());
    glCallList(mesh_list(c, *it.mesh));
    glPopMatrix();
  }
}

void seg_color(int obj, int link) {
  unsigned o = (unsigned)(obj + 1), l = (unsigned)(link + 1);
  glColor4ub(o & 255, (o >> 8) & 255, l & 255, (l >> 8) & 255);
}

// only_obj >= 0: draw only that object (only_link >= 0: only that link)
void draw_world(GLContext &c, World &w, Mode mode, int only_obj, int only_link) {
  static const float grey[4] = {0.5f, 0.5f, 0.5f, 1.0f};
  for (Object *o : w.objects) {
    if (!o || (only_obj >= 0 && o->id != only_obj)) continue;
    if (o->kind == CN_BODY) {
      if (mode == SEG) seg_color(o->id, -1);
      draw_items(c, o->shape->draw, o->rb->getWorldTransform(), mode, o->rgba);
    } else {
      const Model &m = *o->model;
      for (size_t l = 0; l < m.links.size(); ++l) {
        if (only_link >= 0 && (int)l != only_link) continue;
        if (mode == SEG) seg_color(o->id, (int)l);
        const float *ov = o->link_rgba[l][3] >= 0 ? o->link_rgba[l].data() : nullptr;
        bool any_color = false;
        for (auto &it : m.links[l].visual) any_color |= it.has_color;
        draw_items(c, m.links[l].visual, o->link_pose[l], mode, ov ? ov : (any_color ? nullptr : grey));
      }
    }
  }
}

void begin_frame(Mode mode) {
  glDisable(GL_DITHER);
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  // Closed shapes are seen from outside only: a camera inside its robot's housing (Pepper's
  // depth camera lies inside the head sphere) looks out through it.
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  if (mode == SEG) {
    glClearColor(0, 0, 0, 0);
    glDisable(GL_LIGHTING);
    glShadeModel(GL_FLAT);
  } else {
    glClearColor(0.75f, 0.8f, 0.85f, 1.0f);
    glEnable(GL_LIGHTING);
    glEnable(GL_LIGHT0);
    glEnable(GL_NORMALIZE);
    glEnable(GL_COLOR_MATERIAL);
    glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
    glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
    GLfloat amb[4] = {0.35f, 0.35f, 0.35f, 1}, dif[4] = {0.7f, 0.7f, 0.7f, 1}, zero[4] = {0, 0, 0, 1};
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, zero);
    glLightfv(GL_LIGHT0, GL_AMBIENT, amb);
    glLightfv(GL_LIGHT0, GL_DIFFUSE, dif);
    glLightfv(GL_LIGHT0, GL_SPECULAR, zero);
    glShadeModel(GL_SMOOTH);
  }
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void set_light() {
  // directional light from above and behind the camera (eye coordinates)
  GLfloat dir[4] = {0.3f, 0.6f, 1.0f, 0.0f};
  glLightfv(GL_LIGHT0, GL_POSITION, dir);
}

inline void decode_seg(const unsigned char *px, int &obj, int &link) {
  obj = (int)(px[0] | (px[1] << 8)) - 1;
  link = (int)(px[2] | (px[3] << 8)) - 1;
}

void write_png_file(const char *path, const unsigned char *rgb, int w, int h) {
  FILE *f = fopen(path, "wb");
  if (!f) fail(CN_E_FILE, "cannot open '%s' for writing: %s", path, strerror(errno));
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    fclose(f);
    if (png) png_destroy_write_struct(&png, nullptr);
    fail(CN_E_RENDER, "libpng could not be initialised");
  }
  std::vector<png_bytep> rows(h);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    fclose(f);
    fail(CN_E_FILE, "libpng failed writing '%s'", path);
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, w, h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 3);
  for (int y = 0; y < h; ++y) rows[y] = (png_bytep)(rgb + (size_t)y * w * 3);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (fclose(f) != 0) fail(CN_E_FILE, "cannot finish writing '%s'", path);
}

void render_impl(World &w, const Camera &cam, unsigned char *rgb, double *depth, int *seg) {
  std::lock_guard<std::recursive_mutex> gl_lock(gl_mutex());
  GLContext &c = gl_context(cam.w, cam.h);
  const int W = cam.w, H = cam.h;
  if (rgb || depth) {
    begin_frame(COLOR);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    set_light();
    setup_camera(cam);
    draw_world(c, w, COLOR, -1, -1);
    glFinish();
    if (rgb)
      for (int y = 0; y < H; ++y) {
        const unsigned char *src = c.buf.data() + (size_t)(H - 1 - y) * W * 4;
        unsigned char *dst = rgb + (size_t)y * W * 3;
        for (int x = 0; x < W; ++x) {
          dst[3 * x] = src[4 * x];
          dst[3 * x + 1] = src[4 * x + 1];
          dst[3 * x + 2] = src[4 * x + 2];
        }
      }
    if (depth) {
      std::vector<float> d((size_t)W * H);
      glReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, d.data());
      double n = cam.near_m, f = cam.far_m;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          double v = d[(size_t)(H - 1 - y) * W + x];
          depth[(size_t)y * W + x] = v >= 1.0 ? 0.0 : 2 * f * n / (f + n - (2 * v - 1) * (f - n));
        }
    }
  }
  if (seg) {
    begin_frame(SEG);
    setup_camera(cam);
    draw_world(c, w, SEG, -1, -1);
    glFinish();
    for (int y = 0; y < H; ++y) {
      const unsigned char *src = c.buf.data() + (size_t)(H - 1 - y) * W * 4;
      for (int x = 0; x < W; ++x) decode_seg(src + 4 * x, seg[2 * ((size_t)y * W + x)], seg[2 * ((size_t)y * W + x) + 1]);
    }
  }
}

}  // namespace

btTransform gl_camera(const Camera &cam) {
  btMatrix3x3 c;
  if (cam.convention == CN_CAMERA_OPTICAL) c.setValue(1, 0, 0, 0, -1, 0, 0, 0, -1);
  else c.setValue(0, 0, -1, -1, 0, 0, 0, 1, 0);
  return cam.pose * btTransform(c, btVector3(0, 0, 0));
}

void frustum_half_extents(const Camera &cam, double &right, double &top) {
  top = cam.near_m * std::tan(cam.fov * M_PI / 360.0);
  right = top * cam.w / cam.h;
}

Camera read_camera(const double *cam7, int convention, double fov, int w, int h, double n, double f) {
  Camera c;
  c.pose = read_pose(cam7, "camera pose");
  if (convention != CN_CAMERA_OPTICAL && convention != CN_CAMERA_FORWARD)
    fail(CN_E_ARG, "camera convention %d, expected 0 (optical) or 1 (x forward)", convention);
  c.convention = convention;
  if (!std::isfinite(fov) || fov <= 0 || fov >= 180)
    fail(CN_E_ARG, "field of view %s degrees, expected 0 < fov < 180", num(fov).c_str());
  if (w <= 0 || h <= 0 || w > 8192 || h > 8192)
    fail(CN_E_ARG, "image size %dx%d, expected 1..8192 each", w, h);
  check_positive(n, "near plane");
  check_positive(f, "far plane");
  if (f <= n) fail(CN_E_ARG, "far plane %g is not beyond near plane %g", f, n);
  c.fov = fov;
  c.w = w;
  c.h = h;
  c.near_m = n;
  c.far_m = f;
  return c;
}

btTransform look_at_tf(const btVector3 &eye, const btVector3 &target, btVector3 up, int convention) {
  btVector3 fwd = target - eye;
  if (fwd.length() < 1e-12) fail(CN_E_ARG, "eye and target coincide");
  fwd.normalize();
  if (up.length() < 1e-12) fail(CN_E_ARG, "up vector has zero length");
  up.normalize();
  if (fwd.cross(up).length() < 1e-6) up = std::fabs(fwd.z()) < 0.9 ? btVector3(0, 0, 1) : btVector3(1, 0, 0);
  btMatrix3x3 m;
  if (convention == CN_CAMERA_OPTICAL) {
    btVector3 x = fwd.cross(up).normalized(), y = fwd.cross(x);
    m.setValue(x.x(), y.x(), fwd.x(), x.y(), y.y(), fwd.y(), x.z(), y.z(), fwd.z());
  } else {
    btVector3 y = up.cross(fwd).normalized(), z = fwd.cross(y);
    m.setValue(fwd.x(), y.x(), z.x(), fwd.y(), y.y(), z.y(), fwd.z(), y.z(), z.z());
  }
  return btTransform(m, eye);
}

}  // namespace cn

using namespace cn;

extern "C" {

int cn_render(int wh, const double *cam7, int convention, double fov, int width, int height,
              double near_m, double far_m, unsigned char *rgb, double *depth, int *seg) {
  return guard([&] {
    World &w = world(wh);
    Camera cam = read_camera(cam7, convention, fov, width, height, near_m, far_m);
    render_impl(w, cam, rgb, depth, seg);
    return 0;
  });
}

int cn_write_png(const char *path, const unsigned char *rgb, int width, int height) {
  return guard([&] {
    std::string p = check_str(path, "PNG path");
    check_ptr(rgb, "RGB buffer");
    if (width <= 0 || height <= 0) fail(CN_E_ARG, "image size %dx%d, expected positive", width, height);
    write_png_file(p.c_str(), rgb, width, height);
    return 0;
  });
}

int cn_render_png(int wh, const double *cam7, int convention, double fov, int width,
                  int height, const char *path) {
  return guard([&] {
    World &w = world(wh);
    std::string p = check_str(path, "PNG path");
    Camera cam = read_camera(cam7, convention, fov, width, height, 0.05, 100.0);
    std::vector<unsigned char> rgb((size_t)width * height * 3);
    render_impl(w, cam, rgb.data(), nullptr, nullptr);
    write_png_file(p.c_str(), rgb.data(), width, height);
    return 0;
  });
}

int cn_look_at(const double *eye, const double *target, const double *up, int convention, double *out7) {
  return guard([&] {
    check_ptr(eye, "eye");
    check_ptr(target, "target");
    check_ptr(up, "up vector");
    check_ptr(out7, "pose output");
    for (int i = 0; i < 3; ++i) {
      check_finite(eye[i], "eye coordinate");
      check_finite(target[i], "target coordinate");
      check_finite(up[i], "up coordinate");
    }
    if (convention != CN_CAMERA_OPTICAL && convention != CN_CAMERA_FORWARD)
      fail(CN_E_ARG, "camera convention %d, expected 0 (optical) or 1 (x forward)", convention);
    write_pose(look_at_tf(btVector3(eye[0], eye[1], eye[2]), btVector3(target[0], target[1], target[2]),
                          btVector3(up[0], up[1], up[2]), convention),
               out7);
    return 0;
  });
}

}  // extern "C"

// Collision shapes, render meshes and the mesh cache (assimp).
#include "cn_internal.hpp"

#include <BulletCollision/CollisionShapes/btShapeHull.h>
#include <LinearMath/btConvexHullComputer.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/DefaultLogger.hpp>
#include <atomic>

namespace cn {

static std::atomic<uint64_t> g_mesh_ids{1};
RenderMesh::RenderMesh() : id(g_mesh_ids++) {}
RenderMesh::~RenderMesh() { forget_render_mesh(id); }
void RenderMesh::bounds(btVector3 &lo, btVector3 &hi) const {
  std::call_once(bounds_once_, [this] {
    for (size_t i = 0; i + 2 < pos.size(); i += 3) {
      btVector3 p(pos[i], pos[i + 1], pos[i + 2]);
      if (i == 0) lo_ = hi_ = p;
      lo_.setMin(p);
      hi_.setMax(p);
    }
  });
  lo = lo_;
  hi = hi_;
}

double shape_margin() { return 0.001; }

Shape::~Shape() {
  delete shape;
  for (auto *c : children) delete c;
  delete trimesh;
}

// ---- unit primitives for drawing -------------------------------------------------------------
static void tri(RenderMesh &m, const btVector3 &a, const btVector3 &b, const btVector3 &c,
                const btVector3 *na = nullptr, const btVector3 *nb = nullptr,
                const btVector3 *nc = nullptr) {
  btVector3 n = (b - a).cross(c - a);
  if (n.length2() > 0) n.normalize();
  const btVector3 *v[3] = {&a, &b, &c};
  const btVector3 *ns[3] = {na ? na : &n, nb ? nb : &n, nc ? nc : &n};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      m.pos.push_back((float)(*v[i])[k]);
      m.nrm.push_back((float)(*ns[i])[k]);
    }
}

static RenderMeshP build_box() {
  auto m = std::make_shared<RenderMesh>();
  for (int axis = 0; axis < 3; ++axis)
    for (int s = -1; s <= 1; s += 2) {
      btVector3 n(0, 0, 0), u(0, 0, 0), v(0, 0, 0);
      n[axis] = s;
      u[(axis + 1) % 3] = 1;
      v[(axis + 2) % 3] = 1;
      if (s < 0) std::swap(u, v);
      btVector3 c = n * 0.5;
      btVector3 p0 = c - u * 0.5 - v * 0.5, p1 = c + u * 0.5 - v * 0.5, p2 = c + u * 0.5 + v * 0.5,
                p3 = c - u * 0.5 + v * 0.5;
      tri(*m, p0, p1, p2);
      tri(*m, p0, p2, p3);
    }
  return m;
}

static RenderMeshP build_sphere() {
  auto m = std::make_shared<RenderMesh>();
  const int nu = 16, nv = 10;
  auto pt = [&](int i, int j) {
    double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
    return btVector3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
  };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      btVector3 a = pt(i, j), b = pt(i, j + 1), c = pt(i + 1, j + 1), d = pt(i + 1, j);
      if (j > 0) tri(*m, a, b, d, &a, &b, &d);
      if (j < nv - 1) tri(*m, b, c, d, &b, &c, &d);
    }
  return m;
}

static RenderMeshP build_round(bool cone) {
  auto m = std::make_shared<RenderMesh>();
  const int n = 20;
  for (int i = 0; i < n; ++i) {
    double a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * (i + 1) / n;
    btVector3 b0(cos(a0), sin(a0), -0.5), b1(cos(a1), sin(a1), -0.5);
    btVector3 bc(0, 0, -0.5), tc(0, 0, 0.5);
    tri(*m, bc, b1, b0);
    if (cone) {
      btVector3 n0 = btVector3(cos(a0), sin(a0), 1).normalized(),
                n1 = btVector3(cos(a1), sin(a1), 1).normalized();
      tri(*m, b0, b1, tc, &n0, &n1, &n0);
    } else {
      btVector3 t0(cos(a0), sin(a0), 0.5), t1(cos(a1), sin(a1), 0.5);
      btVector3 n0(cos(a0), sin(a0), 0), n1(cos(a1), sin(a1), 0);
      tri(*m, b0, b1, t1, &n0, &n1, &n1);
      tri(*m, b0, t1, t0, &n0, &n1, &n0);
      tri(*m, tc, t0, t1);
    }
  }
  return m;
}

RenderMeshP unit_box() { static RenderMeshP m = build_box(); return m; }
RenderMeshP unit_sphere() { static RenderMeshP m = build_sphere(); return m; }
RenderMeshP unit_cylinder() { static RenderMeshP m = build_round(false); return m; }
RenderMeshP unit_cone() { static RenderMeshP m = build_round(true); return m; }
RenderMeshP plane_quad() {
  static RenderMeshP m = [] {
    auto q = std::make_shared<RenderMesh>();
    btVector3 a(-100, -100, 0), b(100, -100, 0), c(100, 100, 0), d(-100, 100, 0);
    tri(*q, a, b, c);
    tri(*q, a, c, d);
    return RenderMeshP(q);
  }();
  return m;
}

static RenderItem item(RenderMeshP m, const btVector3 &scale,
                       const btTransform &t = btTransform::getIdentity()) {
  RenderItem it;
  it.mesh = std::move(m);
  it.scale = scale;
  it.local = t;
  return it;
}

// ---- primitive shapes -------------------------------------------------------------------------
ShapeP make_plane(const btVector3 &n, double c) {
  auto s = std::make_shared<Shape>();
  s->shape = new btStaticPlaneShape(n, c);
  s->kind = 0;
  s->dims[0] = n.x(); s->dims[1] = n.y(); s->dims[2] = n.z(); s->dims[3] = c;
  btVector3 z(0, 0, 1);
  btQuaternion q = (n.cross(z).length2() < 1e-12)
                       ? (n.z() > 0 ? btQuaternion::getIdentity() : btQuaternion(1, 0, 0, 0))
                       : btQuaternion(z.cross(n).normalized(), z.angle(n));
  s->draw.push_back(item(plane_quad(), btVector3(1, 1, 1), btTransform(q, n * c)));
  return s;
}

ShapeP make_box(double sx, double sy, double sz) {
  auto s = std::make_shared<Shape>();
  s->shape = new btBoxShape(btVector3(sx / 2, sy / 2, sz / 2));
  s->shape->setMargin(std::min(shape_margin(), std::min(sx, std::min(sy, sz)) / 4));
  s->kind = 1;
  s->dims[0] = sx; s->dims[1] = sy; s->dims[2] = sz;
  s->draw.push_back(item(unit_box(), btVector3(sx, sy, sz)));
  return s;
}

ShapeP make_sphere(double r) {
  auto s = std::make_shared<Shape>();
  s->shape = new btSphereShape(r);
  s->kind = 2;
  s->dims[0] = r;
  s->draw.push_back(item(unit_sphere(), btVector3(r, r, r)));
  return s;
}

ShapeP make_cylinder(double r, double h) {
  auto s = std::make_shared<Shape>();
  s->shape = new btCylinderShapeZ(btVector3(r, r, h / 2));
  s->shape->setMargin(std::min(shape_margin(), std::min(r, h) / 4));
  s->kind = 3;
  s->dims[0] = r; s->dims[1] = h;
  s->draw.push_back(item(unit_cylinder(), btVector3(r, r, h)));
  return s;
}

ShapeP make_cone(double r, double h) {
  auto s = std::make_shared<Shape>();
  s->shape = new btConeShapeZ(r, h);
  s->shape->setMargin(shape_margin());
  s->kind = 4;
  s->dims[0] = r; s->dims[1] = h;
  s->draw.push_back(item(unit_cone(), btVector3(r, r, h)));
  return s;
}

static btCollisionShape *hull_of(const std::vector<btVector3> &pts) {
  auto *h = new btConvexHullShape();
  for (auto &p : pts) h->addPoint(p, false);
  h->setMargin(shape_margin());
  h->recalcLocalAabb();
  if (pts.size() > 64) {
    btShapeHull sh(h);
    sh.buildHull(h->getMargin());
    auto *r = new btConvexHullShape();
    for (int i = 0; i < sh.numVertices(); ++i) r->addPoint(sh.getVertexPointer()[i], false);
    r->setMargin(shape_margin());
    r->recalcLocalAabb();
    delete h;
    return r;
  }
  return h;
}

// The exact convex hull of PTS: only its corner points are kept, none dropped. (HULL_OF keeps at
// most the 42-odd support points of fixed directions when given more than 64 points, which
// leaves out corners of large flat faces: a plate's underside would come out tilted.)
static btCollisionShape *exact_hull_of(const std::vector<btVector3> &pts) {
  btConvexHullComputer hc;
  hc.compute(&pts[0].x(), (int)sizeof(btVector3), (int)pts.size(), 0, 0);
  if (hc.vertices.size() < 4) return hull_of(pts);  // flat or degenerate: keep every point
  auto *h = new btConvexHullShape();
  for (int i = 0; i < hc.vertices.size(); ++i) h->addPoint(hc.vertices[i], false);
  h->setMargin(shape_margin());
  h->recalcLocalAabb();
  return h;
}

ShapeP make_hull(const double *p, int n) {
  std::vector<btVector3> pts;
  auto rm = std::make_shared<RenderMesh>();
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(p[3 * i + k]))
        fail(CN_E_ARG, "point %d has %s in component %d", i, num(p[3 * i + k]).c_str(), k);
    pts.emplace_back(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
  }
  auto s = std::make_shared<Shape>();
  s->shape = hull_of(pts);
  s->kind = 6;
  // draw: the triangles of the hull
  btShapeHull sh(static_cast<btConvexShape *>(s->shape));
  sh.buildHull(0);
  for (int i = 0; i + 2 < sh.numIndices(); i += 3) {
    const btVector3 *v = sh.getVertexPointer();
    const unsigned *ix = sh.getIndexPointer();
    tri(*rm, v[ix[i]], v[ix[i + 1]], v[ix[i + 2]]);
  }
  s->draw.push_back(item(rm, btVector3(1, 1, 1)));
  return s;
}

// ---- meshes through assimp ---------------------------------------------------------------------
struct MeshData {
  std::vector<std::vector<btVector3>> parts;  // triangle soup per sub-mesh (3 per triangle)
};

static std::mutex g_mesh_mutex;
static std::map<std::string, ShapeP> g_shape_cache;
static std::map<std::string, RenderMeshP> g_render_cache;

static MeshData read_mesh(const std::string &path, const btVector3 &scale) {
  Assimp::Importer imp;
  imp.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // every mesh of the file stays a sub-mesh of its own (pre-transforming would join the meshes
  // that share a material)
  imp.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  const aiScene *sc = imp.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                             aiProcess_PreTransformVertices |
                                             aiProcess_SortByPType);
  if (!sc || !sc->mRootNode)
    fail(CN_E_FILE, "cannot read mesh file '%s': %s", path.c_str(), imp.GetErrorString());
  MeshData d;
  for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
    const aiMesh *m = sc->mMeshes[i];
    std::vector<btVector3> tris;
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace &face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) {
        const aiVector3D &v = m->mVertices[face.mIndices[k]];
        btVector3 p(v.x * scale.x(), v.y * scale.y(), v.z * scale.z());
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
          fail(CN_E_FILE, "mesh file '%s' has a non-finite vertex", path.c_str());
        tris.push_back(p);
      }
    }
    if (!tris.empty()) d.parts.push_back(std::move(tris));
  }
  if (d.parts.empty()) fail(CN_E_FILE, "mesh file '%s' contains no triangles", path.c_str());
  return d;
}

static std::string cache_key(const std::string &path, const btVector3 &s, const char *tag) {
  return fmt("%s|%.9g|%.9g|%.9g|%s", path.c_str(), s.x(), s.y(), s.z(), tag);
}

static RenderMeshP render_of(const MeshData &d) {
  auto rm = std::make_shared<RenderMesh>();
  for (auto &p : d.parts)
    for (size_t i = 0; i + 2 < p.size(); i += 3) tri(*rm, p[i], p[i + 1], p[i + 2]);
  return rm;
}

RenderMeshP load_render_mesh(const std::string &path, const btVector3 &scale) {
  std::string key = cache_key(path, scale, "render");
  {
    std::lock_guard<std::mutex> lock(g_mesh_mutex);
    auto it = g_render_cache.find(key);
    if (it != g_render_cache.end()) return it->second;
  }
  RenderMeshP rm = render_of(read_mesh(path, scale));
  std::lock_guard<std::mutex> lock(g_mesh_mutex);
  g_render_cache[key] = rm;
  return rm;
}

ShapeP load_mesh(const std::string &path, const btVector3 &scale, MeshMode mode) {
  std::string key = cache_key(path, scale, mode == MeshMode::Exact  ? "exact"
                                           : mode == MeshMode::Hulls ? "hulls"
                                                                     : "one-hull");
  {
    std::lock_guard<std::mutex> lock(g_mesh_mutex);
    auto it = g_shape_cache.find(key);
    if (it != g_shape_cache.end()) return it->second;
  }
  MeshData d = read_mesh(path, scale);
  auto s = std::make_shared<Shape>();
  s->kind = 5;
  s->dims[0] = scale.x(); s->dims[1] = scale.y(); s->dims[2] = scale.z();
  if (mode == MeshMode::Exact) {
    s->trimesh = new btTriangleMesh(true, false);
    for (auto &p : d.parts)
      for (size_t i = 0; i + 2 < p.size(); i += 3) s->trimesh->addTriangle(p[i], p[i + 1], p[i + 2]);
    s->shape = new btBvhTriangleMeshShape(s->trimesh, true);
    s->shape->setMargin(shape_margin());
  } else if (mode == MeshMode::OneHull) {
    std::vector<btVector3> all;
    for (auto &p : d.parts) all.insert(all.end(), p.begin(), p.end());
    s->shape = exact_hull_of(all);
  } else {
    auto *comp = new btCompoundShape(false, (int)d.parts.size());
    s->shape = comp;
    for (auto &p : d.parts) {
      btCollisionShape *h = hull_of(p);
      s->children.push_back(h);
      comp->addChildShape(btTransform::getIdentity(), h);
    }
  }
  RenderMeshP rm;
  {
    std::lock_guard<std::mutex> lock(g_mesh_mutex);
    auto it = g_render_cache.find(cache_key(path, scale, "render"));
    if (it != g_render_cache.end()) rm = it->second;
  }
  if (!rm) {
    rm = render_of(d);
    std::lock_guard<std::mutex> lock(g_mesh_mutex);
    g_render_cache[cache_key(path, scale, "render")] = rm;
  }
  s->draw.push_back(item(rm, btVector3(1, 1, 1)));
  std::lock_guard<std::mutex> lock(g_mesh_mutex);
  auto it = g_shape_cache.find(key);
  if (it != g_shape_cache.end()) return it->second;
  g_shape_cache[key] = s;
  return s;
}

}  // namespace cn

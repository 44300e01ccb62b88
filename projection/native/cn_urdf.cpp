// URDF articulated objects: parsing (urdfdom), link bodies, forward kinematics.
#include "cn_internal.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <deque>

namespace cn {

// ---- console_bridge: silence the console, keep the messages for the error text --------------
static thread_local std::string t_urdf_log;
namespace {
class Capture : public console_bridge::OutputHandler {
 public:
  void log(const std::string &text, console_bridge::LogLevel level, const char *, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      if (!t_urdf_log.empty()) t_urdf_log += "; ";
      t_urdf_log += text;
    }
  }
};
Capture g_capture;
struct InstallCapture {
  InstallCapture() {
    console_bridge::useOutputHandler(&g_capture);
    console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  }
} g_install_capture;
}  // namespace

static btTransform to_bt(const urdf::Pose &p) {
  double x, y, z, w;
  p.rotation.getQuaternion(x, y, z, w);
  btQuaternion q(x, y, z, w);
  if (q.length2() < 1e-12) q = btQuaternion::getIdentity();
  return btTransform(q.normalized(), btVector3(p.position.x, p.position.y, p.position.z));
}

static void check_pose_finite(const urdf::Pose &p, const std::string &where) {
  double x, y, z, w;
  p.rotation.getQuaternion(x, y, z, w);
  double v[7] = {p.position.x, p.position.y, p.position.z, x, y, z, w};
  for (double d : v)
    if (!std::isfinite(d)) fail(CN_E_PARSE, "%s has a non-finite origin", where.c_str());
}

// collision shape and draw items of one geometry element
static ShapeP geometry_shape(const urdf::GeometrySharedPtr &g, const std::string &where,
                             MeshMode meshes) {
  if (!g) fail(CN_E_PARSE, "%s has no geometry", where.c_str());
  switch (g->type) {
    case urdf::Geometry::SPHERE: {
      double r = std::static_pointer_cast<urdf::Sphere>(g)->radius;
      if (!(r > 0) || !std::isfinite(r)) fail(CN_E_PARSE, "%s: sphere radius %g", where.c_str(), r);
      return make_sphere(r);
    }
    case urdf::Geometry::BOX: {
      auto d = std::static_pointer_cast<urdf::Box>(g)->dim;
      if (!(d.x > 0 && d.y > 0 && d.z > 0) || !std::isfinite(d.x + d.y + d.z))
        fail(CN_E_PARSE, "%s: box size %g %g %g", where.c_str(), d.x, d.y, d.z);
      return make_box(d.x, d.y, d.z);
    }
    case urdf::Geometry::CYLINDER: {
      auto c = std::static_pointer_cast<urdf::Cylinder>(g);
      if (!(c->radius > 0 && c->length > 0) || !std::isfinite(c->radius + c->length))
        fail(CN_E_PARSE, "%s: cylinder radius %g length %g", where.c_str(), c->radius, c->length);
      return make_cylinder(c->radius, c->length);
    }
    case urdf::Geometry::MESH: {
      auto m = std::static_pointer_cast<urdf::Mesh>(g);
      btVector3 s(m->scale.x, m->scale.y, m->scale.z);
      if (!(s.x() > 0 && s.y() > 0 && s.z() > 0) || !std::isfinite(s.x() + s.y() + s.z()))
        fail(CN_E_PARSE, "%s: mesh scale %g %g %g", where.c_str(), s.x(), s.y(), s.z());
      std::string path;
      try {
        path = resolve_path(m->filename, "");
      } catch (const Error &e) {
        fail(e.code, "%s: %s", where.c_str(), e.msg.c_str());
      }
      try {
        return load_mesh(path, s, meshes);
      } catch (const Error &e) {
        fail(e.code, "%s: %s", where.c_str(), e.msg.c_str());
      }
    }
  }
  fail(CN_E_PARSE, "%s: unknown geometry type", where.c_str());
}

static void append_draw(std::vector<RenderItem> &out, const Shape &s, const btTransform &origin,
                        const float *rgba) {
  for (RenderItem it : s.draw) {
    it.local = origin * it.local;
    if (rgba) {
      for (int i = 0; i < 4; ++i) it.rgba[i] = rgba[i];
      it.has_color = true;
    }
    out.push_back(it);
  }
}

ModelP parse_urdf(const std::string &xml, MeshMode meshes) {
  t_urdf_log.clear();
  urdf::ModelInterfaceSharedPtr m;
  try {
    m = urdf::parseURDF(xml);
  } catch (const std::exception &e) {
    fail(CN_E_PARSE, "malformed URDF: %s", e.what());
  }
  if (!m) {
    std::string msg = t_urdf_log.empty() ? "urdfdom could not parse it" : t_urdf_log;
    t_urdf_log.clear();
    fail(CN_E_PARSE, "malformed URDF: %s", msg.c_str());
  }
  auto model = std::make_shared<Model>();
  model->name = m->getName();
  auto root = m->getRoot();
  if (!root) fail(CN_E_PARSE, "malformed URDF: no root link");
  // links in breadth-first order from the root, joints in the same order
  std::deque<urdf::LinkConstSharedPtr> queue{root};
  std::vector<urdf::LinkConstSharedPtr> links;
  std::vector<urdf::JointSharedPtr> joints;
  while (!queue.empty()) {
    auto l = queue.front();
    queue.pop_front();
    model->link_index[l->name] = (int)links.size();
    links.push_back(l);
    for (auto &j : l->child_joints) {
      joints.push_back(j);
      auto c = m->getLink(j->child_link_name);
      if (!c) fail(CN_E_PARSE, "joint '%s' names unknown child link '%s'", j->name.c_str(), j->child_link_name.c_str());
      queue.push_back(c);
    }
  }
  for (size_t i = 0; i < joints.size(); ++i) model->joint_index[joints[i]->name] = (int)i;
  model->links.resize(links.size());
  model->joints.resize(joints.size());
  for (size_t i = 0; i < joints.size(); ++i) {
    auto &j = joints[i];
    JointM &jm = model->joints[i];
    jm.name = j->name;
    switch (j->type) {
      case urdf::Joint::REVOLUTE: jm.type = CN_JOINT_REVOLUTE; break;
      case urdf::Joint::CONTINUOUS: jm.type = CN_JOINT_CONTINUOUS; break;
      case urdf::Joint::PRISMATIC: jm.type = CN_JOINT_PRISMATIC; break;
      case urdf::Joint::FLOATING: jm.type = CN_JOINT_FLOATING; break;
      case urdf::Joint::PLANAR: jm.type = CN_JOINT_PLANAR; break;
      default: jm.type = CN_JOINT_FIXED; break;
    }
    jm.parent = model->link_index.at(j->parent_link_name);
    jm.child = model->link_index.at(j->child_link_name);
    check_pose_finite(j->parent_to_joint_origin_transform, "joint '" + j->name + "'");
    jm.origin = to_bt(j->parent_to_joint_origin_transform);
    btVector3 ax(j->axis.x, j->axis.y, j->axis.z);
    if (jm.type == CN_JOINT_REVOLUTE || jm.type == CN_JOINT_CONTINUOUS || jm.type == CN_JOINT_PRISMATIC) {
      if (!std::isfinite(ax.length()) || ax.length() < 1e-9)
        fail(CN_E_PARSE, "joint '%s' has axis (%g %g %g)", j->name.c_str(), ax.x(), ax.y(), ax.z());
      ax.normalize();
    }
    jm.axis = ax;
    if (j->limits) {
      jm.lower = j->limits->lower;
      jm.upper = j->limits->upper;
      jm.velocity = j->limits->velocity;
      jm.effort = j->limits->effort;
    }
    model->links[jm.child].parent_joint = (int)i;
  }
  for (size_t i = 0; i < joints.size(); ++i) {
    auto &j = joints[i];
    if (j->mimic && !j->mimic->joint_name.empty()) {
      auto it = model->joint_index.find(j->mimic->joint_name);
      if (it == model->joint_index.end())
        fail(CN_E_PARSE, "joint '%s' mimics unknown joint '%s'", j->name.c_str(), j->mimic->joint_name.c_str());
      JointM &jm = model->joints[i];
      jm.mimic = it->second;
      jm.mult = j->mimic->multiplier;
      jm.offset = j->mimic->offset;
    }
  }
  // resolve mimic chains to their leading joint
  for (auto &jm : model->joints) {
    int steps = 0;
    while (jm.mimic >= 0 && model->joints[jm.mimic].mimic >= 0) {
      const JointM &lead = model->joints[jm.mimic];
      jm.offset = jm.mult * lead.offset + jm.offset;
      jm.mult *= lead.mult;
      jm.mimic = lead.mimic;
      if (++steps > (int)model->joints.size())
        fail(CN_E_PARSE, "mimic joints of '%s' form a cycle", jm.name.c_str());
    }
  }
  model->root = 0;
  for (size_t i = 0; i < links.size(); ++i) {
    auto &l = links[i];
    LinkM &lm = model->links[i];
    lm.name = l->name;
    std::vector<std::pair<ShapeP, btTransform>> parts;
    int k = 0;
    for (auto &c : l->collision_array) {
      std::string where = fmt("collision %d of link '%s'", k++, l->name.c_str());
      check_pose_finite(c->origin, where);
      parts.emplace_back(geometry_shape(c->geometry, where, meshes), to_bt(c->origin));
    }
    if (parts.size() == 1 && parts[0].second == btTransform::getIdentity()) {
      lm.collision = parts[0].first;
    } else if (!parts.empty()) {
      auto s = std::make_shared<Shape>();
      auto *comp = new btCompoundShape(false, (int)parts.size());
      s->shape = comp;
      s->kind = 5;
      for (auto &p : parts) {
        comp->addChildShape(p.second, p.first->shape);
        s->refs.push_back(p.first);
        append_draw(s->draw, *p.first, p.second, nullptr);
      }
      lm.collision = s;
    }
    // visual geometry; on any failure draw the collision geometry instead
    std::vector<RenderItem> vis;
    bool ok = true;
    for (auto &v : l->visual_array) {
      float rgba[4] = {0.5f, 0.5f, 0.5f, 1.0f};
      bool has = false;
      if (v->material) {
        auto &c = v->material->color;
        if (std::isfinite(c.r + c.g + c.b + c.a)) {
          rgba[0] = c.r; rgba[1] = c.g; rgba[2] = c.b; rgba[3] = c.a;
          has = true;
        }
      }
      try {
        check_pose_finite(v->origin, "visual of link '" + l->name + "'");
        ShapeP s;
        if (v->geometry && v->geometry->type == urdf::Geometry::MESH) {
          auto mm = std::static_pointer_cast<urdf::Mesh>(v->geometry);
          btVector3 sc(mm->scale.x, mm->scale.y, mm->scale.z);
          if (!(sc.x() > 0 && sc.y() > 0 && sc.z() > 0)) fail(CN_E_PARSE, "bad visual scale");
          RenderItem it;
          it.mesh = load_render_mesh(resolve_path(mm->filename, ""), sc);
          it.local = to_bt(v->origin);
          if (has) { for (int i2 = 0; i2 < 4; ++i2) it.rgba[i2] = rgba[i2]; it.has_color = true; }
          vis.push_back(it);
        } else {
          s = geometry_shape(v->geometry, "visual of link '" + l->name + "'", MeshMode::Hulls);
          append_draw(vis, *s, to_bt(v->origin), has ? rgba : nullptr);
        }
      } catch (const Error &) {
        ok = false;
      }
    }
    if (ok && !vis.empty()) lm.visual = vis;
    else if (lm.collision) append_draw(lm.visual, *lm.collision, btTransform::getIdentity(), nullptr);
  }
  return model;
}

void robot_new_bodies(World &w, Object &o) {
  const Model &m = *o.model;
  o.link_rb.assign(m.links.size(), nullptr);
  for (size_t i = 0; i < m.links.size(); ++i) {
    if (!m.links[i].collision) continue;
    btRigidBody *rb = new_body(w, o, m.links[i].collision, 0, o.link_pose[i]);
    rb->setUserIndex2((int)i);
    rb->setCollisionFlags(rb->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    rb->setActivationState(DISABLE_DEACTIVATION);
    rb->setFriction(0.8);
    o.link_rb[i] = rb;
    add_rb(w, rb, o.group, o.mask);
  }
}

static Object &robot_link(World &w, int r, int link) {
  Object &o = w.robot(r);
  if (link < 0 || link >= (int)o.model->links.size())
    fail(CN_E_HANDLE, "link index %d out of range 0..%d in articulated object %d", link,
         (int)o.model->links.size() - 1, r);
  return o;
}

static Object &robot_joint(World &w, int r, int joint) {
  Object &o = w.robot(r);
  if (joint < 0 || joint >= (int)o.model->joints.size())
    fail(CN_E_HANDLE, "joint index %d out of range 0..%d in articulated object %d", joint,
         (int)o.model->joints.size() - 1, r);
  return o;
}

}  // namespace cn

using namespace cn;

// Parsed models by URDF text and mesh mode: a plan that rebuilds its world (init-projection)
// does not parse the same kitchen and robot again. Models are immutable and shared; each
// cache is bounded.
static ModelP cached_model(const std::string &xml, MeshMode meshes) {
  static std::unordered_map<std::string, ModelP> cache[3];
  auto &c = cache[static_cast<int>(meshes)];
  auto it = c.find(xml);
  if (it != c.end()) return it->second;
  ModelP m = parse_urdf(xml, meshes);
  if (c.size() >= 16) c.clear();
  c.emplace(xml, m);
  return m;
}

// MODEL with the origins of the joints NAMES given as the texts of <origin> attributes (XYZ,
// RPY), read as the URDF parser reads them; everything else (links, shapes, the sweep checks'
// view of the links) is shared.
static ModelP moved_model(const ModelP &model, int n, const char *const *names,
                          const char *const *xyz, const char *const *rpy) {
  auto m = std::make_shared<Model>();
  m->name = model->name;
  m->links = model->links;
  m->joints = model->joints;
  m->order = model->order;
  m->root = model->root;
  m->link_index = model->link_index;
  m->joint_index = model->joint_index;
  {
    std::lock_guard<std::mutex> lock(model->cache_mu);
    m->sweep_links = model->sweep_links;  // made of link shapes and chains: the same
  }
  for (int i = 0; i < n; ++i) {
    std::string name = check_str(names[i], "joint name");
    auto it = m->joint_index.find(name);
    if (it == m->joint_index.end())
      fail(CN_E_ARG, "model '%s' has no joint '%s' to move", m->name.c_str(), name.c_str());
    urdf::Pose p;
    try {
      p.position.init(check_str(xyz[i], "origin xyz"));
      p.rotation.init(check_str(rpy[i], "origin rpy"));
    } catch (const std::exception &e) {
      fail(CN_E_ARG, "joint '%s': origin xyz \"%s\" rpy \"%s\": %s", name.c_str(), xyz[i], rpy[i],
           e.what());
    }
    check_pose_finite(p, "joint '" + name + "'");
    m->joints[it->second].origin = to_bt(p);
  }
  return m;
}

static MeshMode mesh_mode(int flags) {
  if (flags & ~(CN_URDF_EXACT_MESHES | CN_URDF_SINGLE_HULL))
    fail(CN_E_ARG, "unknown URDF flags %d (known: CN_URDF_EXACT_MESHES = %d, CN_URDF_SINGLE_HULL = %d)",
         flags, CN_URDF_EXACT_MESHES, CN_URDF_SINGLE_HULL);
  if ((flags & CN_URDF_EXACT_MESHES) && (flags & CN_URDF_SINGLE_HULL))
    fail(CN_E_ARG, "URDF flags %d: CN_URDF_EXACT_MESHES and CN_URDF_SINGLE_HULL exclude each other",
         flags);
  return (flags & CN_URDF_EXACT_MESHES)  ? MeshMode::Exact
         : (flags & CN_URDF_SINGLE_HULL) ? MeshMode::OneHull
                                         : MeshMode::Hulls;
}

// A new articulated object of the model M at BASE in W; returns its handle.
static int add_model(World &w, const ModelP &m, const btTransform &base) {
  std::unique_ptr<Object> o(new Object);
  o->kind = CN_ARTICULATED;
  o->model = m;
  o->base = base;
  o->group = 32;
  o->mask = -1;
  o->q.assign(m->joints.size(), 0.0);
  o->link_rgba.assign(m->links.size(), {0.5f, 0.5f, 0.5f, -1.0f});
  o->id = (int)w.objects.size();
  compute_link_poses(*o, o->link_pose);
  robot_new_bodies(w, *o);
  w.objects.push_back(o.release());
  return (int)w.objects.size() - 1;
}

extern "C" {

int cn_robot_add_urdf(int wh, const char *xml, const double *pose, int flags) {
  return guard([&] {
    World &w = world(wh);
    std::string x = check_str(xml, "URDF string");
    btTransform base = read_pose(pose, "base pose");
    return add_model(w, cached_model(x, mesh_mode(flags)), base);
  });
}

int cn_robot_add_urdf_moved(int wh, const char *xml, const double *pose, int flags, int n,
                            const char *const *joint_names, const char *const *xyz,
                            const char *const *rpy) {
  return guard([&] {
    World &w = world(wh);
    std::string x = check_str(xml, "URDF string");
    btTransform base = read_pose(pose, "base pose");
    if (n < 0) fail(CN_E_ARG, "joint count %d, expected >= 0", n);
    if (n > 0) {
      check_ptr(joint_names, "joint name array");
      check_ptr(xyz, "origin xyz array");
      check_ptr(rpy, "origin rpy array");
    }
    return add_model(w, moved_model(cached_model(x, mesh_mode(flags)), n, joint_names, xyz, rpy),
                     base);
  });
}

int cn_robot_name(int wh, int r, const char **out) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    check_ptr(out, "name output");
    *out = o.model->name.c_str();
    return 0;
  });
}

int cn_robot_num_links(int wh, int r) {
  return guard([&] { return (int)world(wh).robot(r).model->links.size(); });
}
int cn_robot_num_joints(int wh, int r) {
  return guard([&] { return (int)world(wh).robot(r).model->joints.size(); });
}
int cn_robot_root_link(int wh, int r) {
  return guard([&] { return world(wh).robot(r).model->root; });
}

int cn_robot_link_name(int wh, int r, int link, const char **out) {
  return guard([&] {
    Object &o = robot_link(world(wh), r, link);
    check_ptr(out, "name output");
    *out = o.model->links[link].name.c_str();
    return 0;
  });
}

int cn_robot_joint_name(int wh, int r, int joint, const char **out) {
  return guard([&] {
    Object &o = robot_joint(world(wh), r, joint);
    check_ptr(out, "name output");
    *out = o.model->joints[joint].name.c_str();
    return 0;
  });
}

int cn_robot_link_index(int wh, int r, const char *name) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    std::string n = check_str(name, "link name");
    auto it = o.model->link_index.find(n);
    if (it == o.model->link_index.end())
      fail(CN_E_NAME, "unknown link '%s' in robot %d ('%s')", n.c_str(), r, o.model->name.c_str());
    return it->second;
  });
}

int cn_robot_joint_index(int wh, int r, const char *name) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    std::string n = check_str(name, "joint name");
    auto it = o.model->joint_index.find(n);
    if (it == o.model->joint_index.end())
      fail(CN_E_NAME, "unknown joint '%s' in robot %d ('%s')", n.c_str(), r, o.model->name.c_str());
    return it->second;
  });
}

int cn_robot_joint_info(int wh, int r, int joint, int *oi, double *od) {
  return guard([&] {
    Object &o = robot_joint(world(wh), r, joint);
    check_ptr(oi, "joint info int output");
    check_ptr(od, "joint info double output");
    const JointM &j = o.model->joints[joint];
    oi[0] = j.type; oi[1] = j.parent; oi[2] = j.child; oi[3] = j.mimic;
    double v[9] = {j.lower, j.upper, j.velocity, j.effort, j.axis.x(), j.axis.y(), j.axis.z(),
                   j.mimic >= 0 ? j.mult : 1.0, j.mimic >= 0 ? j.offset : 0.0};
    for (int i = 0; i < 9; ++i) od[i] = v[i];
    return 0;
  });
}

int cn_robot_link_parent_joint(int wh, int r, int link) {
  return guard([&] { return robot_link(world(wh), r, link).model->links[link].parent_joint; });
}

int cn_robot_link_has_body(int wh, int r, int link) {
  return guard([&] { return robot_link(world(wh), r, link).link_rb[link] ? 1 : 0; });
}

// Each of JOINTS[0..N) a joint index of articulated object O (handle R), each of VALUES finite.
static void check_joint_values(const Object &o, int r, const int *joints, const double *values,
                               int n) {
  const int nj = (int)o.q.size();
  for (int i = 0; i < n; ++i) {
    if (joints[i] < 0 || joints[i] >= nj)
      fail(CN_E_HANDLE, "joint index %d (element %d) out of range 0..%d in articulated object %d",
           joints[i], i, nj - 1, r);
    if (!std::isfinite(values[i]))
      fail(CN_E_ARG, "value of joint '%s' (element %d) is %s, expected a finite number",
           o.model->joints[joints[i]].name.c_str(), i, num(values[i]).c_str());
  }
}

int cn_robot_set_joints(int wh, int r, const int *joints, const double *values, int n) {
  return guard([&] {
    World &w = world(wh);
    Object &o = w.robot(r);
    if (n < 0) fail(CN_E_ARG, "joint count %d, expected >= 0", n);
    if (n == 0) return 0;
    check_ptr(joints, "joint index array");
    check_ptr(values, "joint value array");
    check_joint_values(o, r, joints, values, n);
    static thread_local std::vector<double> old_q;
    old_q = o.q;
    for (int i = 0; i < n; ++i) o.q[joints[i]] = values[i];
    if (o.link_pose.size() == o.model->links.size()) robot_fk_changed(w, o, old_q);
    else robot_fk(w, o);
    move_attached(w, r);
    return 0;
  });
}

int cn_robot_get_joint(int wh, int r, int joint, double *out) {
  return guard([&] {
    Object &o = robot_joint(world(wh), r, joint);
    check_ptr(out, "joint value output");
    *out = joint_value(*o.model, o.q, joint);
    return 0;
  });
}

int cn_robot_get_joints(int wh, int r, double *out, int cap) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    check_output(cap, out, "joint output");
    int n = (int)o.q.size();
    for (int i = 0; i < n && i < cap; ++i) out[i] = joint_value(*o.model, o.q, i);
    return n;
  });
}

int cn_robot_link_poses(int wh, int r, double *out, int cap) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    check_output(cap, out, "pose output");
    int n = (int)o.link_pose.size();
    for (int i = 0; i < n && i < cap; ++i) write_pose(o.link_pose[i], out + 7 * i);
    return n;
  });
}

int cn_robot_link_pose(int wh, int r, int link, double *out) {
  return guard([&] {
    Object &o = robot_link(world(wh), r, link);
    check_ptr(out, "pose output");
    write_pose(o.link_pose[link], out);
    return 0;
  });
}

int cn_robot_link_poses_if(int wh, int r, const int *joints, const double *values, int nj,
                           const int *links, int nl, double *out) {
  return guard([&] {
    Object &o = world(wh).robot(r);
    const Model &m = *o.model;
    if (nj < 0) fail(CN_E_ARG, "joint count %d, expected >= 0", nj);
    if (nl < 0) fail(CN_E_ARG, "link count %d, expected >= 0", nl);
    if (nj > 0) { check_ptr(joints, "joint index array"); check_ptr(values, "joint value array"); }
    if (nl > 0) { check_ptr(links, "link index array"); check_ptr(out, "pose output"); }
    const int nlinks = (int)m.links.size();
    static thread_local std::vector<double> q;
    q = o.q;
    check_joint_values(o, r, joints, values, nj);
    for (int i = 0; i < nj; ++i) q[joints[i]] = values[i];
    static thread_local std::vector<int> path;
    for (int k = 0; k < nl; ++k) {
      int link = links[k];
      if (link < 0 || link >= nlinks)
        fail(CN_E_HANDLE, "link index %d (element %d) out of range 0..%d in articulated object %d",
             link, k, nlinks - 1, r);
      // the joints from the root down to LINK; as ROBOT_FK_CHANGED, a link is computed again
      // from its parent's pose when its joint's value differs or its parent was computed again
      path.clear();
      for (int l = link; m.links[l].parent_joint >= 0; l = m.joints[m.links[l].parent_joint].parent)
        path.push_back(m.links[l].parent_joint);
      btTransform pose = o.link_pose[m.root];
      bool dirty = false;
      for (auto it = path.rbegin(); it != path.rend(); ++it) {
        const JointM &jm = m.joints[*it];
        double v = joint_value(m, q, *it);
        if (!dirty && v == joint_value(m, o.q, *it)) {
          pose = o.link_pose[jm.child];
        } else {
          dirty = true;
          pose = child_pose(jm, pose, v);
        }
      }
      write_pose(pose, out + 7 * k);
    }
    return 0;
  });
}

int cn_robot_set_self_collision(int wh, int r, int on) {
  return guard([&] {
    world(wh).robot(r).self_collision = on != 0;
    return 0;
  });
}

}  // extern "C"

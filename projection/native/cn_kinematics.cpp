// Forward kinematics of articulated objects: their links' poses from the base pose and the
// joint values (every link, or those a changed joint moves), the bodies moved there, and the
// objects rigidly attached to them carried along.
#include "cn_internal.hpp"

#include <cstring>

namespace cn {

double model_joint_value(const Model &m, const std::vector<double> &q, int j) {
  return joint_value(m, q, j);
}

void compute_link_poses(const Object &o, std::vector<btTransform> &out) {
  compute_link_poses(*o.model, o.base, o.q, out);
}

// Every link pose of model M (those NEEDED, when given) into OUT, from BASE down the joints in
// model order, each child placed by POSE(joint index, parent pose, joint value).
template <class Pose>
static void place_links(const Model &m, const btTransform &base, const std::vector<double> &q,
                        std::vector<btTransform> &out, const std::vector<char> *needed, Pose pose) {
  out.resize(m.links.size());
  out[m.root] = base;
  for (size_t j = 0; j < m.joints.size(); ++j) {
    const JointM &jm = m.joints[j];
    if (needed && !(*needed)[jm.child]) continue;
    out[jm.child] = pose((int)j, out[jm.parent], joint_value(m, q, (int)j));
  }
}

void compute_link_poses(const Model &m, const btTransform &base, const std::vector<double> &q,
                        std::vector<btTransform> &out, const std::vector<char> *needed) {
  place_links(m, base, q, out, needed, [&m](int j, const btTransform &parent, double v) {
    return child_pose(m.joints[j], parent, v);
  });
}

void compute_link_poses_of(const Model &m, const btTransform &base, const std::vector<double> &q,
                           std::vector<btTransform> &out, const std::vector<int> &joints) {
  out[m.root] = base;
  for (int j : joints) {
    const JointM &jm = m.joints[j];
    out[jm.child] = child_pose(jm, out[jm.parent], joint_value(m, q, j));
  }
}

// The rotation of revolute joint J of O at value V, kept for the value last asked for (bit for
// bit; no joint value has the bits of kNoRotation, a NaN): the same matrix CHILD_POSE makes.
static constexpr uint64_t kNoRotation = 0x7ff8deadbeef0001ULL;

static const btMatrix3x3 &joint_rotation(Object &o, int j, const JointM &jm, double v) {
  size_t n = o.model->joints.size();
  if (o.joint_rot.size() != n) {
    o.joint_rot.assign(n, btMatrix3x3::getIdentity());
    o.joint_rot_bits.assign(n, kNoRotation);
  }
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  if (o.joint_rot_bits[j] != bits) {
    o.joint_rot[j] = btMatrix3x3(btQuaternion(jm.axis, v));
    o.joint_rot_bits[j] = bits;
  }
  return o.joint_rot[j];
}

// CHILD_POSE of joint J of O, a revolute joint's rotation taken from JOINT_ROTATION.
static inline btTransform child_pose_of(Object &o, int j, const btTransform &parent, double v) {
  const JointM &jm = o.model->joints[j];
  if (jm.type != CN_JOINT_REVOLUTE && jm.type != CN_JOINT_CONTINUOUS) return child_pose(jm, parent, v);
  btTransform t = parent * jm.origin;
  t.setBasis(t.getBasis() * joint_rotation(o, j, jm, v));
  return t;
}

void robot_fk(World &w, Object &o) {
  // COMPUTE_LINK_POSES of O, the joints' rotations kept
  place_links(*o.model, o.base, o.q, o.link_pose, nullptr,
              [&o](int j, const btTransform &parent, double v) {
                return child_pose_of(o, j, parent, v);
              });
  for (size_t i = 0; i < o.link_rb.size(); ++i)
    if (o.link_rb[i]) teleport_rb(w, o.link_rb[i], o.link_pose[i]);
}

// After O's joint values changed from OLD_Q (its base kept): the poses of the links a changed
// joint moves, computed as ROBOT_FK does (the others are those it would compute again), and
// their bodies moved.
void robot_fk_changed(World &w, Object &o, const std::vector<double> &old_q) {
  const Model &m = *o.model;
  static thread_local std::vector<char> dirty;
  dirty.assign(m.links.size(), 0);
  for (size_t j = 0; j < m.joints.size(); ++j) {
    const JointM &jm = m.joints[j];
    double v = joint_value(m, o.q, (int)j);
    if (!dirty[jm.parent] && v == joint_value(m, old_q, (int)j)) continue;
    dirty[jm.child] = 1;
    o.link_pose[jm.child] = child_pose_of(o, (int)j, o.link_pose[jm.parent], v);
  }
  for (size_t i = 0; i < o.link_rb.size(); ++i)
    if (dirty[i] && o.link_rb[i]) teleport_rb(w, o.link_rb[i], o.link_pose[i]);
}

void move_attached(World &w, int parent, int depth) {
  if (w.attachments.empty() || depth > 16) return;
  for (auto &a : w.attachments) {
    if (a.parent != parent || a.loose) continue;
    Object *p = w.objects[a.parent], *c = w.objects[a.obj];
    if (!p || !c) continue;
    btTransform t = frame_pose(*p, a.link) * a.rel;
    if (c->kind == CN_BODY) teleport_rb(w, c->rb, t);
    else { c->base = t; robot_fk(w, *c); }
    move_attached(w, a.obj, depth + 1);
  }
}

}  // namespace cn

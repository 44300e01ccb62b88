// The paths of moving frames along a robot's sweep-checked motion (cn_robot_sweep_paths): where
// a link, or a body the robot carries, is at evenly spaced times of the motion, the base moving
// and the joints interpolated as the sweep check moves them (struct Sweep, cn_sweep_impl.hpp).
#include "cn_sweep_impl.hpp"

using namespace cn;
using namespace cn::sweep;

namespace {

struct Frame {
  int link = -1;                          // robot link it hangs from; -1: fixed where it is
  btTransform rel = btTransform::getIdentity();  // its pose relative to that link (or the world)
};

// Where FRAMES2 entry I (obj, link) hangs from ROBOT: a link of it, a body it carries rigidly
// (through other bodies, perhaps), or a body that stays where it is.
Frame frame_of(World &w, const Object &robot, int obj, int link, int i) {
  Frame f;
  if (obj == robot.id) {
    int nl = (int)robot.link_rb.size();
    if (link < 0 || link >= nl)
      fail(CN_E_HANDLE, "frame %d: link %d out of range 0..%d of robot %d", i, link, nl - 1, obj);
    f.link = link;
    return f;
  }
  Object &b = w.obj(obj, "frame's object");
  if (b.kind != CN_BODY) fail(CN_E_ARG, "frame %d: object %d is neither robot %d nor a body", i, obj, robot.id);
  if (link != -1) fail(CN_E_ARG, "frame %d: link %d of body %d, expected -1", i, link, obj);
  btTransform rel = btTransform::getIdentity();
  for (int child = obj, depth = 0; depth <= 16; ++depth) {
    const Attachment *a = nullptr;
    for (const Attachment &x : w.attachments)
      if (x.obj == child && !x.loose) a = &x;
    if (!a) break;
    rel = a->rel * rel;
    if (a->parent == robot.id) {
      f.link = a->link;
      f.rel = rel;
      return f;
    }
    child = a->parent;
  }
  f.rel = b.rb->getWorldTransform();
  return f;
}

}  // namespace

extern "C" {

int cn_robot_sweep_paths(int wh, int rh, const double *base_from7, const double *q_from,
                         const double *base_to7, const double *q_to, int nq, const int *frames2,
                         int n_frames, int steps, double *out3) {
  return guard([&] {
    World &w = world(wh);
    Sweep s(w, nullptr, 0, 1e-3, 0);
    Object &r = s.set_robot_motion(rh, base_from7, q_from, base_to7, q_to, nq);
    const int nj = nq;  // every joint of the robot
    if (n_frames < 0) fail(CN_E_ARG, "frame count %d, expected >= 0", n_frames);
    if (steps < 1 || steps > 10000) fail(CN_E_ARG, "steps %d, expected 1 .. 10000", steps);
    if (n_frames == 0) return 0;
    check_ptr(frames2, "frame list");
    check_ptr(out3, "path output");
    std::vector<Frame> frames;
    for (int i = 0; i < n_frames; ++i) frames.push_back(frame_of(w, r, frames2[2 * i], frames2[2 * i + 1], i));
    const Model &md = *r.model;
    std::vector<char> needed(md.links.size(), 0);
    for (const Frame &f : frames)
      for (int l = f.link; l >= 0 && !needed[l];) {
        needed[l] = 1;
        int pj = md.links[l].parent_joint;
        l = pj >= 0 ? md.joints[pj].parent : -1;
      }
    std::vector<btTransform> lp;
    s.qt.assign(nj, 0);
    for (int k = 0; k <= steps; ++k) {
      double t = (double)k / steps;
      for (int j = 0; j < nj; ++j) s.qt[j] = s.q0[j] + t * (s.q1[j] - s.q0[j]);
      compute_link_poses(md, s.base_at(t), s.qt, lp, &needed);
      for (int i = 0; i < n_frames; ++i) {
        const Frame &f = frames[i];
        btVector3 p = f.link >= 0 ? lp[f.link] * f.rel.getOrigin() : f.rel.getOrigin();
        double *o = out3 + 3 * ((size_t)i * (steps + 1) + k);
        o[0] = p.x();
        o[1] = p.y();
        o[2] = p.z();
      }
    }
    return n_frames;
  });
}

}  // extern "C"

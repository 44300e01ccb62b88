// The reach map of a kinematic chain (see cn_reach_map.hpp).
#include "cn_reach_map.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace cn {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

constexpr double kCell = 0.005;          // metres: the grid's cell
constexpr double kFirstStep = 0.0075;    // how far the tip moves, at most, from one sample of a
constexpr double kLargestStep = 0.05;    // joint to the next (grown while over the budget)
constexpr long kSampleBudget = 1500000;  // tip positions computed for one map

// The moving transform of joint j at value q: rotation about or translation along its axis.
void joint_motion(const ReachJoint &j, double q, Mat3 &R, Vec3 &t) {
  if (j.prismatic) {
    R.setIdentity();
    t = j.axis * q;
  } else {
    R = Eigen::AngleAxisd(q, j.axis).toRotationMatrix();
    t.setZero();
  }
}

// The value a joint keeps while the map is built: 0 within its range, else the nearer end.
double rest_value(const ReachJoint &j) { return std::min(j.upper, std::max(j.lower, 0.0)); }

// The tip in the first joint's frame for the values q of joints 1 .. n-1 (q[0] unused).
Vec3 tip_in_first(const std::vector<ReachJoint> &joints, const std::vector<double> &q,
                  const Vec3 &tip_p) {
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
  for (size_t i = 1; i < joints.size(); ++i) {
    p += R * joints[i].p;
    R = R * joints[i].R;
    Mat3 M;
    Vec3 t;
    joint_motion(joints[i], q[i], M, t);
    p += R * t;
    R = R * M;
  }
  return p + R * tip_p;
}

// Joints 1 .. n-1 that move the tip at all (a wrist turning about the tip does not).
std::vector<size_t> moving_joints(const std::vector<ReachJoint> &joints, const Vec3 &tip_p) {
  std::vector<size_t> out;
  SplitMix64 draw{0x5eed};
  std::vector<double> q(joints.size());
  for (size_t i = 1; i < joints.size(); ++i) {
    bool moves = false;
    for (int trial = 0; trial < 8 && !moves; ++trial) {
      for (size_t k = 1; k < joints.size(); ++k) q[k] = draw.uniform(joints[k].lower, joints[k].upper);
      Vec3 a = tip_in_first(joints, q, tip_p);
      for (double v : {joints[i].lower, joints[i].upper, 0.5 * (joints[i].lower + joints[i].upper)}) {
        q[i] = v;
        if ((tip_in_first(joints, q, tip_p) - a).norm() > 1e-9) moves = true;
      }
    }
    if (moves) out.push_back(i);
  }
  return out;
}

// A bound on the tip's distance from joint i's origin over all configurations; with `axis`,
// from joint i's axis (the next joint's offset counts only across the axis: turning about the
// axis keeps that part).
double reach_after(const std::vector<ReachJoint> &joints, size_t i, const Vec3 &tip_p,
                   bool axis = false) {
  double r = tip_p.norm();
  for (size_t k = i + 1; k < joints.size(); ++k) {
    Vec3 off = joints[k].p;
    if (axis && k == i + 1) off -= off.dot(joints[i].axis) * joints[i].axis;
    r += off.norm();
    if (joints[k].prismatic) r += std::max(std::fabs(joints[k].lower), std::fabs(joints[k].upper));
  }
  return r;
}

}  // namespace

ReachMap::ReachMap(const std::vector<ReachJoint> &joints, const Vec3 &tip_p) {
  if (joints.empty() || joints[0].prismatic) return;
  for (const ReachJoint &j : joints)
    if (!(std::isfinite(j.lower) && std::isfinite(j.upper) && j.lower <= j.upper)) return;
  first_R_ = joints[0].R;
  first_p_ = joints[0].p;
  first_axis_ = joints[0].axis;
  for (double step = kFirstStep; step <= kLargestStep * 1.0001; step *= 1.25)
    if (build(joints, tip_p, step)) return;
  cells_.clear();
}

bool ReachMap::build(const std::vector<ReachJoint> &joints, const Vec3 &tip_p, double step) {
  const double cell = kCell;
  const std::vector<size_t> moving = moving_joints(joints, tip_p);
  // per moving joint: its samples' spacing and count
  std::vector<double> spacing(moving.size());
  std::vector<long> count(moving.size());
  long total = 1;
  double slack = 0;  // how far any configuration's tip lies from the nearest sample's
  for (size_t l = 0; l < moving.size(); ++l) {
    const ReachJoint &j = joints[moving[l]];
    double r = j.prismatic ? 1.0 : std::max(reach_after(joints, moving[l], tip_p, true), 1e-9);
    double range = j.upper - j.lower;
    count[l] = range > 0 ? std::max(2L, (long)std::ceil(range / (step / r)) + 1) : 1;
    spacing[l] = count[l] > 1 ? range / (double)(count[l] - 1) : 0;
    slack += r * spacing[l] / 2;
    total *= count[l];
    if (total > kSampleBudget) return false;
  }
  const double bound = reach_after(joints, 0, tip_p);
  const int widen = (int)std::floor((kMaxTolerance + slack) / cell) + 1;
  const double margin = (widen + 1) * cell;
  h0_ = -(bound + margin);
  n_rho_ = (int)std::ceil((bound + margin) / cell) + 1;
  n_h_ = (int)std::ceil(2 * (bound + margin) / cell) + 1;
  cells_.assign((size_t)n_rho_ * n_h_, 0);

  // Level l turns the moving joint moving[l]; what lies between two moving joints (fixed
  // transforms, other joints at their rest values) is folded into one constant transform
  // before it, and what follows the last one into the tip point.
  const size_t levels = moving.size();
  std::vector<Mat3> CR(levels);
  std::vector<Vec3> Cp(levels);
  Mat3 R = Mat3::Identity();
  Vec3 p = Vec3::Zero();
  size_t next = 0;
  for (size_t i = 1; i < joints.size(); ++i) {
    p += R * joints[i].p;
    R = R * joints[i].R;
    if (next < levels && moving[next] == i) {
      CR[next] = R;
      Cp[next] = p;
      R.setIdentity();
      p.setZero();
      ++next;
    } else {
      Mat3 M;
      Vec3 t;
      joint_motion(joints[i], rest_value(joints[i]), M, t);
      p += R * t;
      R = R * M;
    }
  }
  const Vec3 tail = p + R * tip_p;  // the tip in the last moving joint's moving frame
  if (levels == 0) {
    mark(tail);
  } else {
    // per level and sample: the level's rotation (constant part included) and translation;
    // the last level's samples map straight to the tip point
    std::vector<std::vector<Mat3>> M(levels);
    std::vector<std::vector<Vec3>> t(levels);
    for (size_t l = 0; l < levels; ++l) {
      const ReachJoint &j = joints[moving[l]];
      M[l].resize(count[l]);
      t[l].resize(count[l]);
      for (long s = 0; s < count[l]; ++s) {
        Mat3 Rq;
        Vec3 tq;
        joint_motion(j, j.lower + s * spacing[l], Rq, tq);
        M[l][s] = CR[l] * Rq;
        t[l][s] = Cp[l] + CR[l] * tq;
        if (l + 1 == levels) t[l][s] += M[l][s] * tail;
      }
    }
    // an odometer over the levels but the last (their prefix transforms recomputed from the
    // level that changed); the last level runs in the inner loop
    const size_t last = levels - 1;
    std::vector<Mat3> Rs(levels);
    std::vector<Vec3> ps(levels);
    Rs[0].setIdentity();
    ps[0].setZero();
    std::vector<long> at(levels, 0);
    size_t changed = 0;
    for (;;) {
      for (size_t l = changed; l < last; ++l) {
        ps[l + 1] = ps[l] + Rs[l] * t[l][at[l]];
        Rs[l + 1] = Rs[l] * M[l][at[l]];
      }
      for (long s = 0; s < count[last]; ++s) mark(ps[last] + Rs[last] * t[last][s]);
      long l = (long)last - 1;
      while (l >= 0 && ++at[l] == count[l]) at[l--] = 0;
      if (l < 0) break;
      changed = (size_t)l;
    }
  }

  // widen the marked cells by `widen` in rho and h (a square: more than any distance needs)
  std::vector<unsigned char> rows(cells_.size(), 0);
  for (int i = 0; i < n_rho_; ++i)
    for (int k = 0; k < n_h_; ++k)
      if (cells_[(size_t)i * n_h_ + k])
        for (int d = std::max(0, k - widen); d <= std::min(n_h_ - 1, k + widen); ++d)
          rows[(size_t)i * n_h_ + d] = 1;
  std::fill(cells_.begin(), cells_.end(), 0);
  for (int i = 0; i < n_rho_; ++i)
    for (int k = 0; k < n_h_; ++k)
      if (rows[(size_t)i * n_h_ + k])
        for (int d = std::max(0, i - widen); d <= std::min(n_rho_ - 1, i + widen); ++d)
          cells_[(size_t)d * n_h_ + k] = 1;
  return true;
}

void ReachMap::mark(const Vec3 &x) {
  double h = x.dot(first_axis_);
  double rho = (x - h * first_axis_).norm();
  int i = (int)std::floor(rho / kCell), k = (int)std::floor((h - h0_) / kCell);
  if (i >= 0 && i < n_rho_ && k >= 0 && k < n_h_) cells_[(size_t)i * n_h_ + k] = 1;
}

bool ReachMap::may_reach(const Vec3 &goal, double tolerance) const {
  if (cells_.empty() || !(tolerance <= kMaxTolerance) || !goal.allFinite()) return true;
  Vec3 x = first_R_.transpose() * (goal - first_p_);
  double h = x.dot(first_axis_);
  double rho = (x - h * first_axis_).norm();
  double fi = std::floor(rho / kCell), fk = std::floor((h - h0_) / kCell);
  if (!(fi >= 0 && fi < n_rho_ && fk >= 0 && fk < n_h_)) return false;
  return cells_[(size_t)fi * n_h_ + (size_t)fk] != 0;
}

namespace {
// FNV-1a over the bytes of a double
void hash_double(uint64_t &h, double x) {
  unsigned char b[sizeof x];
  std::memcpy(b, &x, sizeof x);
  for (unsigned char c : b) h = (h ^ c) * 0x100000001b3ULL;
}
}  // namespace

uint64_t ReachMap::Key(const std::vector<ReachJoint> &joints, const Vec3 &tip_p) {
  uint64_t h = 0xcbf29ce484222325ULL;
  // the map's own constants: a map built with others is another map
  for (double x : {kCell, kFirstStep, kLargestStep, (double)kSampleBudget, kMaxTolerance, 1.0})
    hash_double(h, x);
  hash_double(h, (double)joints.size());
  for (const ReachJoint &j : joints) {
    for (int i = 0; i < 9; ++i) hash_double(h, j.R(i));
    for (int i = 0; i < 3; ++i) hash_double(h, j.p(i));
    for (int i = 0; i < 3; ++i) hash_double(h, j.axis(i));
    hash_double(h, j.prismatic ? 1.0 : 0.0);
    hash_double(h, j.lower);
    hash_double(h, j.upper);
  }
  for (int i = 0; i < 3; ++i) hash_double(h, tip_p(i));
  return h;
}

void ReachMap::save(const std::vector<ReachJoint> &joints, const Vec3 &tip_p,
                    double *params) const {
  const uint64_t key = Key(joints, tip_p);
  params[0] = (double)(key >> 32);
  params[1] = (double)(key & 0xffffffffULL);
  for (int i = 0; i < 9; ++i) params[2 + i] = first_R_(i);
  for (int i = 0; i < 3; ++i) params[11 + i] = first_p_(i);
  for (int i = 0; i < 3; ++i) params[14 + i] = first_axis_(i);
  params[17] = h0_;
  params[18] = n_rho_;
  params[19] = n_h_;
}

std::unique_ptr<ReachMap> ReachMap::restore(const std::vector<ReachJoint> &joints,
                                            const Vec3 &tip_p, const double *params,
                                            const unsigned char *cells, size_t n) {
  const uint64_t key = Key(joints, tip_p);
  if (params[0] != (double)(key >> 32) || params[1] != (double)(key & 0xffffffffULL))
    return nullptr;
  const double rho = params[18], hs = params[19];
  if (!(rho >= 0 && hs >= 0 && rho == std::floor(rho) && hs == std::floor(hs) &&
        rho * hs == (double)n && rho < 1e6 && hs < 1e6))
    return nullptr;
  std::unique_ptr<ReachMap> m(new ReachMap());
  for (int i = 0; i < 9; ++i) m->first_R_(i) = params[2 + i];
  for (int i = 0; i < 3; ++i) m->first_p_(i) = params[11 + i];
  for (int i = 0; i < 3; ++i) m->first_axis_(i) = params[14 + i];
  m->h0_ = params[17];
  m->n_rho_ = (int)rho;
  m->n_h_ = (int)hs;
  m->cells_.assign(cells, cells + n);
  return m;
}

}  // namespace cn

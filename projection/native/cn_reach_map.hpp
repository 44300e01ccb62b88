// Where the tip of a kinematic chain can be: a necessary condition for an IK goal's position,
// so that a goal out of the arm's reach is given up before any solver iteration.
//
// The chain's first joint turns everything after it about its axis, so whether a point is a
// tip position (for some value of that joint, its limits left aside) depends only on the
// point's distance from that axis (rho) and its height along it (h).  The map is a grid over
// (rho, h) marking the cells a dense sampling of the other joints reaches, widened by as many
// cells as any configuration can lie from a sampled one, plus the largest position tolerance
// it answers for: "no" means no configuration within the joint limits comes that close.
#pragma once
#include <Eigen/Core>

#include <cstdint>
#include <memory>

#include <vector>

namespace cn {

// splitmix64: uniform doubles that depend on the seed alone, the same on every platform
struct SplitMix64 {
  uint64_t state;
  double uniform(double lo, double hi) {
    state += 0x9e3779b97f4a7c15ULL;
    uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) * 0x1.0p-53;
  }
};

struct ReachJoint {
  Eigen::Matrix3d R;     // fixed transform from the previous joint's moving frame
  Eigen::Vector3d p;
  Eigen::Vector3d axis;  // unit, in the joint frame
  bool prismatic = false;
  double lower = 0, upper = 0;  // the range the joint can take (revolute without limits: a turn)
};

class ReachMap {
 public:
  // Largest position tolerance (metres) the map answers for; a query with a larger one is
  // always "maybe".
  static constexpr double kMaxTolerance = 0.002;

  // An empty map (every answer "maybe") when the chain does not suit: a first joint that is
  // not revolute, an unlimited prismatic joint, or more samples than the budget at a step of 5 cm.
  // JOINTS from the chain's base to its tip, TIP_P the tip's offset from the last joint's frame.
  ReachMap(const std::vector<ReachJoint> &joints, const Eigen::Vector3d &tip_p);

  // False only when no configuration within the limits (the first joint's left aside) puts
  // the tip within `tolerance` of `goal` (in the chain's base frame).
  bool may_reach(const Eigen::Vector3d &goal, double tolerance) const;

  // The map as numbers, to keep beyond the process (see cn_chain_reach_map_get): kParams
  // doubles, the first two the halves of Key(joints, tip_p), and the cells.
  static constexpr int kParams = 20;
  static uint64_t Key(const std::vector<ReachJoint> &joints, const Eigen::Vector3d &tip_p);
  void save(const std::vector<ReachJoint> &joints, const Eigen::Vector3d &tip_p,
            double *params) const;
  const std::vector<unsigned char> &cells() const { return cells_; }
  // The map of `params` and `cells` (from save) when they are a map of JOINTS and TIP_P, else
  // nullptr.
  static std::unique_ptr<ReachMap> restore(const std::vector<ReachJoint> &joints,
                                           const Eigen::Vector3d &tip_p, const double *params,
                                           const unsigned char *cells, size_t n);


 private:
  ReachMap() = default;
  bool build(const std::vector<ReachJoint> &joints, const Eigen::Vector3d &tip_p, double step);
  void mark(const Eigen::Vector3d &tip_in_first);
  Eigen::Matrix3d first_R_;  // base frame -> first joint frame
  Eigen::Vector3d first_p_, first_axis_;
  double h0_ = 0;             // h of the grid's first row
  int n_rho_ = 0, n_h_ = 0;
  std::vector<unsigned char> cells_;  // n_rho_ x n_h_, row-major by rho
};

}  // namespace cn

// Trajectories in TUM format and their time association, as the evo tool reads and pairs them.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace unav::evaluation {

/// A trajectory file or pairing is unusable; what() names the file, line and rule.
class TrajectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Stamped poses T_WB (body in world). Stamps in seconds, strictly increasing.
struct Trajectory {
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d> poses;

  size_t size() const { return stamps.size(); }
  bool empty() const { return stamps.empty(); }
  void push_back(double stamp, const Eigen::Isometry3d& pose) {
    stamps.push_back(stamp);
    poses.push_back(pose);
  }
  /// Sum of distances between consecutive positions [m].
  double path_length() const;
};

/// Reads `timestamp tx ty tz qx qy qz qw` lines ('#' comments and blank lines skipped). Throws
/// TrajectoryError "<file>:<line>: ..." for a wrong column count, a non-number, NaN/Inf, a
/// quaternion far from unit norm, or a timestamp not greater than the previous one.
Trajectory read_tum(const std::string& path);
/// Writes TUM lines with full precision (stamps with 9 decimals). Throws on I/O failure.
void write_tum(const std::string& path, const Trajectory& traj);

/// Pairs poses by nearest timestamp like evo's associate_trajectories: each stamp of the shorter
/// trajectory takes the nearest stamp of the longer one (after adding `offset_s` to the second
/// trajectory's stamps) when it is within `max_diff_s`. Returns the two reduced trajectories in
/// the argument order. Throws TrajectoryError when no pair is found (no overlap in time).
std::pair<Trajectory, Trajectory> associate(const Trajectory& first, const Trajectory& second, double max_diff_s = 0.01,
                                            double offset_s = 0.0);

}  // namespace unav::evaluation

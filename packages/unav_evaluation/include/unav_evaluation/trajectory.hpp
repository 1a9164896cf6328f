// Trajectories in TUM format and their time association, as the evo tool reads and pairs them.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace unav::evaluation {

/// A trajectory file or pairing is unusable; what() names the file, line and rule.
class TrajectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Stamped poses T_WB (body in world). Stamps in seconds, non-decreasing (TUM files may repeat a
/// stamp, as evo accepts); KITTI files have none and get their index (0, 1, 2, ...).
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

/// A trajectory recorded on disk as it grows, so a node that records for hours holds O(1) memory:
/// each pose is appended to a binary file (the stamp and the 3x4 [R | t], as doubles: load() gives
/// back the same bits), created at the first pose. The file is the run's record until remove(), also
/// when the process is killed. Throws TrajectoryError naming the file on I/O failure.
class TrajectorySpool {
 public:
  TrajectorySpool() = default;
  explicit TrajectorySpool(std::string path) : path_(std::move(path)) {}
  void push_back(double stamp, const Eigen::Isometry3d& pose);
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  double last_stamp() const { return last_stamp_; }  ///< of the last pose (0 when empty)
  /// Every pose so far, in order.
  Trajectory load();
  /// Deletes the file; the spool is empty again.
  void remove();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  size_t size_ = 0;
  double last_stamp_ = 0.0;
};

/// An estimator's corrected history from the paths it publishes (a SLAM republishes its
/// trajectory after bundle adjustment and loop closing, perhaps only its latest poses: a bounded
/// path): every stamp keeps the pose of the latest path that held it. over(odometry) is the whole
/// run: the odometry before the history's first stamp, the history, the odometry after its last.
class PathHistory {
 public:
  void update(const Trajectory& path);
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }
  Trajectory over(const Trajectory& odometry) const;

 private:
  std::map<int64_t, std::pair<double, Eigen::Isometry3d>> poses_;  ///< by stamp [ns]
};

/// Reads `timestamp tx ty tz qx qy qz qw` lines ('#' comments and blank lines skipped; commas
/// accepted as separators). Throws TrajectoryError "<file>:<line>: column N (name): ..." for a
/// wrong column count, a non-number, NaN/Inf, a quaternion far from unit norm, or a timestamp
/// before the previous one (equal stamps are kept, as evo keeps them).
Trajectory read_tum(const std::string& path);
/// Reads a KITTI odometry poses file: 12 numbers per line, the row-major 3x4 [R | t] of the pose;
/// no stamps (the pose index is used). Throws for a wrong count, a non-number, NaN/Inf or a
/// rotation that is not orthonormal (within 1e-3).
Trajectory read_kitti(const std::string& path);
/// Reads an EuRoC/ASL CSV (state_groundtruth_estimate0/data.csv or any csv of the kind):
/// `timestamp[ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z[, ...]` ('#' header skipped, extra columns
/// ignored, as evo reads it). Stamps become seconds.
Trajectory read_euroc_csv(const std::string& path);

/// The trajectory file formats: "tum", "kitti", "euroc". Throws TrajectoryError otherwise.
enum class TrajectoryFormat { kTum, kKitti, kEuroc };
TrajectoryFormat trajectory_format_from_string(const std::string& name);
Trajectory read_trajectory(const std::string& path, TrajectoryFormat format);
/// Writes the 12-number KITTI lines (stamps dropped).
void write_kitti(const std::string& path, const Trajectory& traj);
/// Writes TUM lines with full precision (stamps with 9 decimals). Throws on I/O failure.
void write_tum(const std::string& path, const Trajectory& traj);

/// Pairs poses by nearest timestamp like evo's associate_trajectories: each stamp of the shorter
/// trajectory takes the nearest stamp of the longer one (after adding `offset_s` to the second
/// trajectory's stamps) when it is within `max_diff_s`; among equally near stamps the first one
/// (numpy's argmin), also when a stamp repeats. Returns the two reduced trajectories in the
/// argument order. Throws TrajectoryError when no pair is found (no overlap in time).
std::pair<Trajectory, Trajectory> associate(const Trajectory& first, const Trajectory& second, double max_diff_s = 0.01,
                                            double offset_s = 0.0);

/// Pairs by index, as evo compares KITTI files (no association): both must have the same number
/// of poses ("trajectories must have same number of poses" otherwise).
std::pair<Trajectory, Trajectory> pair_by_index(const Trajectory& first, const Trajectory& second);

}  // namespace unav::evaluation

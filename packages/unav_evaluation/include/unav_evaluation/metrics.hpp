// Umeyama alignment and the APE / RPE metrics, defined exactly as the evo tool defines them.
#pragma once

#include <string>
#include <vector>

#include "unav_common/sim3.hpp"
#include "unav_evaluation/trajectory.hpp"

namespace unav::evaluation {

/// y = s * R * x + t (the workspace's one Sim(3), unav_common/sim3.hpp).
using Sim3 = unav::common::Sim3;

/// Least-squares similarity (Umeyama 1991) mapping points `src` onto `dst` (columns are
/// points, at least 3 non-collinear for a unique rotation). With `with_scale` false, s = 1.
/// Throws TrajectoryError on size mismatch or degenerate input.
Sim3 umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale);

enum class Alignment { kNone, kSE3, kSim3, kScaleOnly };
/// Parses "none", "se3", "sim3", "scale"; throws TrajectoryError otherwise.
Alignment alignment_from_string(const std::string& name);
/// The name alignment_from_string() reads ("none", "se3", "sim3", "scale").
const char* alignment_name(Alignment a);

/// Aligns `est` to `ref` (already associated, same size) as evo's `align` does, using the
/// first `n` poses (all when n < 0): positions are scaled by s, then T = (R, t) is applied on
/// the left of every pose. Returns the transform used.
Sim3 align(Trajectory& est, const Trajectory& ref, Alignment mode, int n = -1);

/// Which part of the pose error a metric measures (evo's PoseRelation).
enum class PoseRelation { kTranslation, kRotationAngleRad, kRotationAngleDeg, kFull };

/// APE: E_i = ref_i^-1 * est_i for associated, aligned pairs; one error per pose.
std::vector<double> ape(const Trajectory& ref, const Trajectory& est, PoseRelation relation);

enum class DeltaUnit { kFrames, kMeters };
struct RpeOptions {
  double delta = 1.0;
  DeltaUnit unit = DeltaUnit::kFrames;
  bool all_pairs = false;
  double rel_tol = 0.1;  ///< relative path tolerance for kMeters with all_pairs
};
/// RPE: for index pairs (i, j) chosen on the estimate as evo's id_pairs_from_delta chooses
/// them, E = (ref_i^-1 ref_j)^-1 (est_i^-1 est_j). Throws TrajectoryError if no pair exists.
std::vector<double> rpe(const Trajectory& ref, const Trajectory& est, PoseRelation relation,
                        const RpeOptions& options = {});
/// Index pairs used by rpe() (exposed for tests and reports).
std::vector<std::pair<size_t, size_t>> rpe_pairs(const Trajectory& est, const RpeOptions& options);

/// evo's statistics of an error vector (std is the population standard deviation).
struct Statistics {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0, sse = 0;
  size_t count = 0;
};
Statistics statistics(const std::vector<double>& errors);

}  // namespace unav::evaluation

#include "unav_evaluation/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/SVD>

namespace unav::evaluation {
namespace {

double rotation_angle(const Eigen::Matrix3d& R) {
  // Angle of the rotation, robust near 0 and pi (clamped acos of the trace).
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

double error_of(const Eigen::Isometry3d& E, PoseRelation relation) {
  switch (relation) {
    case PoseRelation::kTranslation:
      return E.translation().norm();
    case PoseRelation::kRotationAngleRad:
      return rotation_angle(E.linear());
    case PoseRelation::kRotationAngleDeg:
      return rotation_angle(E.linear()) * 180.0 / M_PI;
    case PoseRelation::kFull:
      return (E.matrix() - Eigen::Matrix4d::Identity()).norm();
  }
  return 0.0;
}

void require_same_size(const Trajectory& ref, const Trajectory& est) {
  if (ref.size() != est.size() || ref.empty())
    throw TrajectoryError("trajectories must be associated first: " + std::to_string(ref.size()) + " reference vs " +
                          std::to_string(est.size()) + " estimated poses");
}

}  // namespace

Sim3 umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  if (src.cols() != dst.cols() || src.cols() < 2)
    throw TrajectoryError("umeyama: need the same number (>= 2) of source and destination points, got " +
                          std::to_string(src.cols()) + " and " + std::to_string(dst.cols()));
  // evo's rules: two points suffice, collinear sets and any scale are accepted.
  unav::common::UmeyamaOptions options;
  options.with_scale = with_scale;
  options.min_points = 2;
  const unav::common::UmeyamaResult r = unav::common::Umeyama(src, dst, options);
  if (with_scale && r.source_variance <= 0.0)
    throw TrajectoryError("umeyama: source points have no spread (all identical)");
  return r.S;
}

Alignment alignment_from_string(const std::string& name) {
  if (name == "none") return Alignment::kNone;
  if (name == "se3") return Alignment::kSE3;
  if (name == "sim3") return Alignment::kSim3;
  if (name == "scale") return Alignment::kScaleOnly;
  throw TrajectoryError("alignment '" + name + "' is unknown (known: none, se3, sim3, scale)");
}

const char* alignment_name(Alignment a) {
  switch (a) {
    case Alignment::kNone:
      return "none";
    case Alignment::kSE3:
      return "se3";
    case Alignment::kSim3:
      return "sim3";
    case Alignment::kScaleOnly:
      return "scale";
  }
  return "none";
}

Sim3 align(Trajectory& est, const Trajectory& ref, Alignment mode, int n) {
  require_same_size(ref, est);
  Sim3 T;
  if (mode == Alignment::kNone) return T;
  const size_t count = n < 0 ? est.size() : std::min(est.size(), static_cast<size_t>(n));
  Eigen::Matrix3Xd src(3, count), dst(3, count);
  for (size_t i = 0; i < count; ++i) {
    src.col(static_cast<Eigen::Index>(i)) = est.poses[i].translation();
    dst.col(static_cast<Eigen::Index>(i)) = ref.poses[i].translation();
  }
  const Sim3 u = umeyama(src, dst, mode == Alignment::kSim3 || mode == Alignment::kScaleOnly);
  if (mode == Alignment::kScaleOnly) {
    T.s = u.s;
  } else {
    T = u;
    if (mode == Alignment::kSE3) T.s = 1.0;
  }
  for (auto& P : est.poses) {
    P.translation() = T.R * (T.s * P.translation()) + T.t;
    P.linear() = T.R * P.linear();
  }
  return T;
}

std::vector<double> ape(const Trajectory& ref, const Trajectory& est, PoseRelation relation) {
  require_same_size(ref, est);
  std::vector<double> e(ref.size());
  for (size_t i = 0; i < ref.size(); ++i) e[i] = error_of(ref.poses[i].inverse() * est.poses[i], relation);
  return e;
}

std::vector<std::pair<size_t, size_t>> rpe_pairs(const Trajectory& est, const RpeOptions& o) {
  std::vector<std::pair<size_t, size_t>> pairs;
  const size_t n = est.size();
  if (!(o.delta > 0.0)) throw TrajectoryError("RPE delta must be > 0, got " + std::to_string(o.delta));
  if (o.unit == DeltaUnit::kFrames) {
    const size_t d = static_cast<size_t>(o.delta);
    if (d < 1 || static_cast<double>(d) != o.delta)
      throw TrajectoryError("RPE delta in frames must be a positive integer, got " + std::to_string(o.delta));
    if (o.all_pairs) {
      for (size_t i = 0; i + d < n; ++i) pairs.emplace_back(i, i + d);
    } else {
      for (size_t i = 0; i + d < n; i += d) pairs.emplace_back(i, i + d);
    }
  } else if (o.all_pairs) {
    // For each start, the end whose path length from it is nearest delta, within tolerance.
    std::vector<double> acc(n, 0.0);
    for (size_t i = 1; i < n; ++i)
      acc[i] = acc[i - 1] + (est.poses[i].translation() - est.poses[i - 1].translation()).norm();
    const double tol = o.delta * o.rel_tol;
    for (size_t i = 0; i < n; ++i) {
      const double target = acc[i] + o.delta;
      const size_t j =
          static_cast<size_t>(std::lower_bound(acc.begin() + static_cast<long>(i), acc.end(), target) - acc.begin());
      size_t best = n;
      double best_res = tol;
      for (size_t k : {j == 0 ? 0 : j - 1, j}) {
        if (k <= i || k >= n) continue;
        const double res = std::abs(acc[k] - acc[i] - o.delta);
        if (res <= best_res) {
          best_res = res;
          best = k;
        }
      }
      if (best < n) pairs.emplace_back(i, best);
    }
  } else {
    // evo: a pose closes a segment when the path accumulated since the last one reaches delta;
    // consecutive segment ends form the pairs.
    std::vector<size_t> ids;
    double path = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (i > 0) path += (est.poses[i].translation() - est.poses[i - 1].translation()).norm();
      if (path >= o.delta) {
        ids.push_back(i);
        path = 0.0;
      }
    }
    for (size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  }
  if (pairs.empty())
    throw TrajectoryError("RPE delta " + std::to_string(o.delta) + (o.unit == DeltaUnit::kFrames ? " frames" : " m") +
                          " gives no pose pairs among " + std::to_string(n) + " poses: use a smaller delta");
  return pairs;
}

std::vector<double> rpe(const Trajectory& ref, const Trajectory& est, PoseRelation relation, const RpeOptions& o) {
  require_same_size(ref, est);
  std::vector<double> e;
  for (const auto& [i, j] : rpe_pairs(est, o)) {
    const Eigen::Isometry3d Q = ref.poses[i].inverse() * ref.poses[j];
    const Eigen::Isometry3d P = est.poses[i].inverse() * est.poses[j];
    e.push_back(error_of(Q.inverse() * P, relation));
  }
  return e;
}

Statistics statistics(const std::vector<double>& errors) {
  Statistics s;
  s.count = errors.size();
  if (errors.empty()) return s;
  const double n = static_cast<double>(errors.size());
  for (double e : errors) s.sse += e * e;
  s.mean = std::accumulate(errors.begin(), errors.end(), 0.0) / n;
  s.rmse = std::sqrt(s.sse / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  const size_t m = sorted.size() / 2;
  s.median = sorted.size() % 2 ? sorted[m] : 0.5 * (sorted[m - 1] + sorted[m]);
  return s;
}

}  // namespace unav::evaluation

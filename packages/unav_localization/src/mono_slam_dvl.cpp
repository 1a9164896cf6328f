// MonoSlam, DVL-aided: the DVL's bottom velocity integrated between keyframes puts each map in
// metres (a least-squares scale, no gravity needed: the SLAM's own attitude rotates the velocity
// into the map) and, once metric, constrains every bundle adjustment with the displacement
// between consecutive keyframes, as ROV navigation filters fuse the DVL.
//
// With p = s c + R_wc o_c (body origin; c the camera centre in map units, o_c the DVL origin in the
// camera frame, metric) the DVL displacement d_ij over [t_i, t_j] gives
//   s (c_j - c_i) = d_ij - (R_wc_j - R_wc_i) o_c,
// one linear equation in s per keyframe pair; s by least squares over the recent pairs.
#include "mono_slam_impl.hpp"

#include <iterator>
#include <utility>

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

namespace {
constexpr double kMaxGapS = 0.5;  // a longer gap between readings: not covered
// A scaling whose pairs disagree by more than this (RMS of s a - y over RMS of y) is refused:
// a wrong attitude, a track on moving things, or a DVL that lost the bottom.
constexpr double kMaxScaleResidual = 0.3;
constexpr std::size_t kMinPairs = 5;
}  // namespace

auto MonoSlam::Impl::AddDvl(double stamp, const Eigen::Vector3d& v, bool valid) -> void {
  if (!dvl_on) return;
  const double last = !dvl_pending.empty() ? dvl_pending.back().t : !dvl.empty() ? dvl.back().t : -INFINITY;
  if (!std::isfinite(stamp) || (valid && !v.allFinite()) || stamp <= last) {
    ++stats.dvl_samples_rejected;
    return;
  }
  dvl_pending.push_back({stamp, valid ? v : Eigen::Vector3d::Zero(), valid});
}

auto MonoSlam::Impl::AdmitSensorData(double stamp) -> void {
  for (; !imu_pending.empty() && imu_pending.front().t < stamp; imu_pending.pop_front())
    imu.push_back(imu_pending.front());
  for (; !dvl_pending.empty() && dvl_pending.front().t < stamp; dvl_pending.pop_front())
    dvl.push_back(dvl_pending.front());
  while (!imu.empty() && imu.front().t < stamp - kImuHistoryS) imu.pop_front();
  while (!dvl.empty() && dvl.front().t < stamp - kDvlHistoryS) dvl.pop_front();
}

auto MonoSlam::Impl::DvlDisplacement(double t0, double t1, const Eigen::Quaterniond& q_wd0,
                                     const Eigen::Quaterniond& q_wd1) const -> std::optional<Eigen::Vector3d> {
  if (!(t1 > t0) || dvl.empty() || dvl.front().t > t0 || dvl.back().t < t1) return std::nullopt;
  // The readings from the last one at or before t0 to the first at or after t1.
  auto first = std::upper_bound(dvl.begin(), dvl.end(), t0, [](double t, const DvlSample& m) { return t < m.t; });
  --first;  // dvl.front().t <= t0: exists
  auto last = std::lower_bound(first, dvl.end(), t1, [](const DvlSample& m, double t) { return m.t < t; });
  const auto v_w = [&](const DvlSample& m) {
    const double a = std::clamp((m.t - t0) / (t1 - t0), 0.0, 1.0);
    return Eigen::Vector3d(q_wd0.slerp(a, q_wd1) * m.v);
  };
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (auto k = first; k != last; ++k) {
    const auto n = std::next(k);
    if (!k->valid || !n->valid || n->t - k->t > kMaxGapS) return std::nullopt;
    // Linear between the readings, clipped to [t0, t1]: the trapezoid of the clipped ends.
    const double a = std::max(k->t, t0), b = std::min(n->t, t1);
    if (b <= a) continue;
    const double span = n->t - k->t;
    const Eigen::Vector3d vk = v_w(*k), dv = v_w(*n) - vk;  // each reading rotated once
    const Eigen::Vector3d va = vk + dv * ((a - k->t) / span);
    const Eigen::Vector3d vb = vk + dv * ((b - k->t) / span);
    d += 0.5 * (va + vb) * (b - a);
  }
  return d;
}

auto MonoSlam::Impl::DvlSteps(const std::vector<const KeyFrame*>& kfs) const -> std::vector<DvlStep> {
  const Eigen::Matrix3d R_cd = T_dc.linear().transpose();
  std::vector<DvlStep> out;
  for (std::size_t k = 1; k < kfs.size(); ++k) {
    const Eigen::Isometry3d Ti = kfs[k - 1]->T_cw.inverse(), Tj = kfs[k]->T_cw.inverse();
    const auto d = DvlDisplacement(kfs[k - 1]->stamp, kfs[k]->stamp, Eigen::Quaterniond(Ti.linear() * R_cd),
                                   Eigen::Quaterniond(Tj.linear() * R_cd));
    if (d) out.push_back({kfs[k - 1]->id, kfs[k]->id, Ti, Tj, *d});
  }
  return out;
}

auto MonoSlam::Impl::TryDvlScale() -> std::string {
  if (dvl.empty() || metric_stage >= static_cast<int>(std::size(kMetricStageSpan))) return "";
  const std::vector<const KeyFrame*> kfs = RecentKeyFrames(dvl.front().t, kMetricInitKeyframes);
  const double span = opt.dvl_init_window_s * kMetricStageSpan[metric_stage];
  if (kfs.size() < kMinMetricInitKeyframes || kfs.back()->stamp - kfs.front()->stamp < span) return "";
  const Eigen::Vector3d o_c = T_dc.inverse().translation();
  double aa = 0.0, ay = 0.0, yy = 0.0, travel = 0.0;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;  // (a, y)
  for (const DvlStep& st : DvlSteps(kfs)) {
    const Eigen::Vector3d a = st.T_wc_j.translation() - st.T_wc_i.translation();
    const Eigen::Vector3d y = st.d_w - (st.T_wc_j.linear() - st.T_wc_i.linear()) * o_c;
    pairs.emplace_back(a, y);
    aa += a.squaredNorm();
    ay += a.dot(y);
    yy += y.squaredNorm();
    travel += st.d_w.norm();
  }
  if (pairs.size() < kMinPairs || travel < opt.dvl_min_travel_m) return "";  // not yet: wait for motion
  const double s = aa > 0.0 ? ay / aa : 0.0;
  double rr = 0.0;
  for (const auto& [a, y] : pairs) rr += (s * a - y).squaredNorm();
  const double residual = yy > 0.0 ? std::sqrt(rr / yy) : 1.0;
  if (!(s > 0.0) || !std::isfinite(s) || residual > kMaxScaleResidual) {
    ++stats.dvl_rejections;
    char why[160];
    std::snprintf(why, sizeof(why), "DVL scaling not accepted: %.4f m per map unit, pairs disagree by %.0f %%", s,
                  100.0 * residual);
    return std::exchange(dvl_rejection_said, true) ? "" : why;
  }
  ++(metric_stage == 0 ? stats.dvl_inits : stats.dvl_refinements);
  ApplyMetricScale(s);
  stats.dvl_scale = s;
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "DVL %s over %zu keyframe pairs (%.1f s, %.2f m): %.4f m per map unit, %.1f %% residual",
                metric_stage == 1 ? "scaling" : "refinement", pairs.size(), kfs.back()->stamp - kfs.front()->stamp,
                travel, s, 100.0 * residual);
  return buf;
}

auto MonoSlam::Impl::DvlFactors(std::size_t count) const -> std::vector<BodyDisplacementFactor> {
  std::vector<BodyDisplacementFactor> out;
  if (!dvl_on || !opt.dvl_factors || metric_stage == 0 || dvl.empty()) return out;
  const Eigen::Vector3d o_c = T_dc.inverse().translation();
  for (const DvlStep& st : DvlSteps(RecentKeyFrames(dvl.front().t, count))) {
    BodyDisplacementFactor f;
    f.kf_i = st.kf_i;
    f.kf_j = st.kf_j;
    f.o_c = o_c;
    f.d_w = st.d_w;
    f.sigma = opt.dvl_factor_sigma_m + opt.dvl_factor_sigma_ratio * st.d_w.norm();
    out.push_back(f);
  }
  return out;
}

}  // namespace unav::localization

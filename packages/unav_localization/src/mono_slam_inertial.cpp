// MonoSlam, inertial: IMU samples, preintegration between keyframes and the inertial-only
// initialisation that puts each map in metres (unav_localization/inertial_init.hpp).
#include "mono_slam_impl.hpp"
#include "unav_localization/inertial_init.hpp"

#include <iterator>
#include <utility>

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

namespace {
constexpr double kCoverSlackS = 0.02;  // a sample this close to an interval's end still covers it
}  // namespace

auto MonoSlam::Impl::AddImu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) -> void {
  if (!inertial) return;
  const double last = !imu_pending.empty() ? imu_pending.back().t : !imu.empty() ? imu.back().t : -INFINITY;
  if (!std::isfinite(stamp) || !gyro.allFinite() || !accel.allFinite() || stamp <= last) {
    ++stats.imu_samples_rejected;
    return;
  }
  imu_pending.push_back({stamp, gyro, accel});
}

auto MonoSlam::Impl::PreintegrateImu(double t0, double t1) const -> ImuPreintegration {
  ImuPreintegration pre({}, imu_noise);
  if (imu.empty() || imu.front().t > t0 + kCoverSlackS || imu.back().t < t1 - kCoverSlackS || t1 <= t0) return pre;
  // From the sample that holds at t0 (the last one at or before it).
  const auto first = std::upper_bound(imu.begin(), imu.end(), t0, [](double t, const ImuSample& m) { return t < m.t; });
  for (auto k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, first - imu.begin() - 1)); k < imu.size(); ++k) {
    const double a = std::max(imu[k].t, t0);
    const double b = std::min(k + 1 < imu.size() ? imu[k + 1].t : t1, t1);
    if (b <= a) {
      if (imu[k].t >= t1) break;
      continue;
    }
    pre.Integrate(imu[k].gyro, imu[k].accel, b - a);
  }
  return pre;
}

auto MonoSlam::Impl::ScaleMap(double s) -> void {
  for (auto& k : map->keyframes) k->T_cw.translation() *= s;
  for (auto& p : map->points) {
    p->X_w *= s;
    p->min_distance *= s;
    p->max_distance *= s;
  }
  for (auto& e : traj) e.T_cr.translation() *= s;
  cur.T_cw.translation() *= s;
  last.T_cw.translation() *= s;
  velocity.translation() *= s;
  for (double& d : recent_steps) d *= s;
  for (auto& [k, v] : vi.velocities) v *= s;  // (the map's units per second)
}

auto MonoSlam::Impl::RecentKeyFrames(double not_before, std::size_t count) const -> std::vector<const KeyFrame*> {
  std::vector<const KeyFrame*> kfs;
  for (const auto& k : map->keyframes)
    if (!k->bad && k->stamp >= not_before) kfs.push_back(k.get());
  std::sort(kfs.begin(), kfs.end(), [](const KeyFrame* a, const KeyFrame* b) { return a->stamp < b->stamp; });
  if (count > 0 && kfs.size() > count) kfs.erase(kfs.begin(), kfs.end() - static_cast<std::ptrdiff_t>(count));
  return kfs;
}

auto MonoSlam::Impl::ApplyMetricScale(double s) -> void {
  ScaleMap(s);
  if (metric_stage == 0 && global_per_metric <= 0.0) {
    // The first map in metres: the global frame becomes metric when it is the first map of the
    // run; a later one keeps the global units the earlier maps were written in.
    G.s = map_number == 0 ? 1.0 : G.s / s;
    global_per_metric = G.s;
    map_sets_global_scale = true;
  } else if (map_sets_global_scale) {
    if (map_number > 0) G.s /= s;  // a better estimate of the same global units per metre
    global_per_metric = G.s;
  } else {
    G.s = global_per_metric;  // continues from the join at the earlier maps' scale
  }
  UpdateGoodPose();
  ++metric_stage;
}

auto MonoSlam::Impl::TryInertialInit() -> std::string {
  if (imu.empty() || metric_stage >= static_cast<int>(std::size(kMetricStageSpan))) return "";
  const std::vector<const KeyFrame*> kfs = RecentKeyFrames(imu.front().t - kCoverSlackS, kMetricInitKeyframes);
  const double span = opt.inertial_init_window_s * kMetricStageSpan[metric_stage];
  if (kfs.size() < kMinMetricInitKeyframes || kfs.back()->stamp - kfs.front()->stamp < span) return "";
  std::vector<Eigen::Isometry3d> poses;
  std::vector<ImuPreintegration> pres;
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    poses.push_back(kfs[k]->T_cw.inverse());
    if (k == 0) continue;
    pres.push_back(PreintegrateImu(kfs[k - 1]->stamp, kfs[k]->stamp));
    if (pres.back().dt() <= 0.0) return "";  // the IMU does not cover it (yet)
  }
  const InertialInitResult r = InertialOnlyInit(poses, pres, T_bc);
  if (!r.ok) {
    ++stats.inertial_rejections;
    // Said once a map (it is tried again at every keyframe).
    return std::exchange(inertial_rejection_said, true) ? "" : "inertial initialisation not accepted: " + r.message;
  }
  ++(metric_stage == 0 ? stats.inertial_inits : stats.inertial_refinements);
  ApplyMetricScale(r.scale);
  StartInertialStates(kfs, r);
  if (opt.inertial_ba) {
    // ORB-SLAM3's VIBA 1 and 2: the whole map with its inertial factors, so that the scale, the
    // gravity and the velocities agree with every keyframe, not only the local window's.
    GlobalBundleAdjustment(map.get(), cam, sigma2, opt.global_ba_iterations, AidingFactors(0));
    cur.T_cw = map->kf(ref_kf).T_cw;  // the frame just made a keyframe moves with it
    has_velocity = false;
  }
  stats.inertial_scale = r.scale;
  const Eigen::Vector3d z_cam = kfs.front()->T_cw.linear().transpose().col(2);
  stats.inertial_gravity_deg = std::acos(std::clamp(r.gravity_w.normalized().dot(z_cam), -1.0, 1.0)) * 180.0 / M_PI;
  char buf[240];
  std::snprintf(buf, sizeof(buf),
                "inertial %s over %zu keyframes (%.1f s): %.4f m per map unit, gravity %.1f deg from the "
                "first camera's axis, gyro bias (%.4f, %.4f, %.4f) rad/s",
                metric_stage == 1 ? "initialisation" : "refinement", kfs.size(), kfs.back()->stamp - kfs.front()->stamp,
                r.scale, stats.inertial_gravity_deg, r.bias.gyro.x(), r.bias.gyro.y(), r.bias.gyro.z());
  return buf;
}

auto MonoSlam::Impl::StartInertialStates(const std::vector<const KeyFrame*>& kfs, const InertialInitResult& r) -> void {
  // The visual-inertial states start from the initialisation's (velocities are metric already).
  vi.g_w = r.gravity_w;
  vi.bias = vi.bias_prior = r.bias;
  const InertialInitOptions init_options;
  vi.gyro_bias_prior_sigma = init_options.gyro_bias_prior_std;
  vi.accel_bias_prior_sigma = init_options.accel_bias_prior_std;
  vi.velocities.clear();
  for (std::size_t k = 0; k < kfs.size() && k < r.velocities.size(); ++k) vi.velocities[kfs[k]->id] = r.velocities[k];
  vi_ready = true;
}

auto MonoSlam::Impl::InertialFactors(std::size_t count) -> std::vector<InertialFactor> {
  std::vector<InertialFactor> out;
  if (!inertial || !vi_ready || !opt.inertial_ba || imu.empty()) return out;
  const std::vector<const KeyFrame*> kfs = RecentKeyFrames(imu.front().t - kCoverSlackS, count);
  const Eigen::Isometry3d T_cb = T_bc.inverse();
  for (std::size_t k = 1; k < kfs.size(); ++k) {
    const int i = kfs[k - 1]->id, j = kfs[k]->id;
    const ImuPreintegration pre = PreintegrateImu(kfs[k - 1]->stamp, kfs[k]->stamp);
    if (pre.dt() <= 0.0) continue;  // not covered (yet)
    if (!vi.velocities.count(j)) {
      const auto vel_i = vi.velocities.find(i);
      if (vel_i == vi.velocities.end()) continue;
      const Eigen::Isometry3d T_wb = kfs[k - 1]->T_cw.inverse() * T_cb;
      vi.velocities[j] = pre.Predict({T_wb.linear(), T_wb.translation(), vel_i->second}, vi.bias, vi.g_w).v_W;
    }
    out.push_back({i, j, pre, T_cb});
  }
  return out;
}

auto MonoSlam::Impl::ImuPredictedPose(double stamp) const -> std::optional<Eigen::Isometry3d> {
  if (!inertial || !vi_ready || !opt.inertial_ba || !opt.imu_prediction || imu.empty()) return std::nullopt;
  // The newest keyframe before `stamp` with a velocity: keyframes are made in time order, so
  // their ids grow with their stamps and the search from the newest ends at the first one (it
  // scanned every keyframe of the run per frame before).
  const KeyFrame* from = nullptr;
  for (auto it = vi.velocities.rbegin(); it != vi.velocities.rend(); ++it) {
    const KeyFrame& k = map->kf(it->first);
    if (!k.bad && k.stamp < stamp) {
      from = &k;
      break;
    }
  }
  if (from == nullptr) return std::nullopt;
  const Eigen::Isometry3d T_wb = from->T_cw.inverse() * T_bc.inverse();
  const NavState at_kf{T_wb.linear(), T_wb.translation(), vi.velocities.at(from->id)};
  const auto predict = [&](double t) -> std::optional<Eigen::Isometry3d> {
    if (t <= from->stamp) return T_wb;
    const ImuPreintegration pre = PreintegrateImu(from->stamp, t);
    if (pre.dt() <= 0.0) return std::nullopt;
    const NavState s = pre.Predict(at_kf, vi.bias, vi.g_w);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = s.R_WB;
    T.translation() = s.p_W;
    return T;
  };
  const std::optional<Eigen::Isometry3d> now = predict(stamp);
  if (!now) return std::nullopt;
  // Anchored at the last tracked frame when there is one: its visual pose and the IMU's motion
  // since (the difference of two predictions from the same keyframe state), so the prediction's
  // error is that of the last frame interval, not of every interval since the keyframe.
  if (last_tracked && last.stamp < stamp && last.stamp >= from->stamp) {
    if (const std::optional<Eigen::Isometry3d> then = predict(last.stamp)) {
      const Eigen::Isometry3d T_wb_last = last.T_cw.inverse() * T_bc.inverse();
      return (T_wb_last * then->inverse() * *now * T_bc).inverse();
    }
  }
  return (*now * T_bc).inverse();
}

auto MonoSlam::Impl::GyroFactors(std::size_t count) const -> std::vector<RelativeRotationFactor> {
  std::vector<RelativeRotationFactor> out;
  // The visual-inertial factors hold the rotation too.
  if (!inertial || !opt.gyro_factors || imu.empty() || (vi_ready && opt.inertial_ba)) return out;
  const std::vector<const KeyFrame*> kfs = RecentKeyFrames(imu.front().t - kCoverSlackS, count);
  const Eigen::Matrix3d R_cb = T_bc.linear().transpose();
  for (std::size_t k = 1; k < kfs.size(); ++k) {
    const ImuPreintegration pre = PreintegrateImu(kfs[k - 1]->stamp, kfs[k]->stamp);
    if (pre.dt() <= 0.0) continue;  // not covered (yet)
    RelativeRotationFactor f;
    f.kf_i = kfs[k - 1]->id;
    f.kf_j = kfs[k]->id;
    f.R_cb = R_cb;
    f.dR_b = pre.delta_R();
    f.sigma = std::sqrt(pre.covariance().topLeftCorner<3, 3>().trace() / 3.0) + opt.gyro_factor_sigma_rad +
              opt.gyro_bias_sigma * pre.dt();
    out.push_back(f);
  }
  return out;
}

}  // namespace unav::localization

// MonoSlam: bookkeeping (trajectory, re-initialisation), the per-frame Track() driver and the
// public API; the stages live in mono_slam_*.cpp.
#include "mono_slam_impl.hpp"

#include <cstdio>

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace)

bool MonoSlamOptions::IsValid(std::string* msg) const {
  auto fail = [msg](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (!orb.IsValid(msg)) return false;
  if (init_orb_features_factor < 1 || init_orb_features_factor > 5)
    return fail("init_orb_features_factor must be in [1, 5], got " + std::to_string(init_orb_features_factor));
  if (!(init_min_parallax_deg > 0 && init_min_parallax_deg < 30))
    return fail("init_min_parallax_deg must be in (0, 30), got " + std::to_string(init_min_parallax_deg));
  if (init_min_points < 20) return fail("init_min_points must be >= 20, got " + std::to_string(init_min_points));
  if (!(init_min_good_ratio >= 0 && init_min_good_ratio <= 1))
    return fail("init_min_good_ratio must be in [0, 1], got " + std::to_string(init_min_good_ratio));
  if (!(init_homography_ratio >= 0 && init_homography_ratio <= 1))
    return fail("init_homography_ratio must be in [0, 1], got " + std::to_string(init_homography_ratio));
  if (init_max_frames < 2) return fail("init_max_frames must be >= 2, got " + std::to_string(init_max_frames));
  if (!(inertial_init_window_s > 0.0 && inertial_init_window_s <= 60.0))
    return fail("inertial_init_window_s must be in (0, 60], got " + std::to_string(inertial_init_window_s));
  // The aiding sensors' settings: {name, value, lower bound, lower bound open, upper bound}.
  struct Bound {
    const char* name;
    double value, lo;
    bool lo_open;
    double hi;
  };
  for (const Bound& b : {Bound{"dvl_init_window_s", dvl_init_window_s, 0.0, true, 60.0},
                         Bound{"dvl_min_travel_m", dvl_min_travel_m, 0.0, false, 100.0},
                         Bound{"dvl_factor_sigma_m", dvl_factor_sigma_m, 0.0, true, 10.0},
                         Bound{"dvl_factor_sigma_ratio", dvl_factor_sigma_ratio, 0.0, false, 1.0},
                         Bound{"gyro_factor_sigma_rad", gyro_factor_sigma_rad, 0.0, true, 1.0},
                         Bound{"gyro_bias_sigma", gyro_bias_sigma, 0.0, false, 1.0}}) {
    if ((b.lo_open ? b.value > b.lo : b.value >= b.lo) && b.value <= b.hi) continue;  // NaN fails both
    char range[64];
    std::snprintf(range, sizeof(range), "%s%g, %g]", b.lo_open ? "(" : "[", b.lo, b.hi);
    return fail(std::string(b.name) + " must be in " + range + ", got " + std::to_string(b.value));
  }
  if (!(clahe_clip >= 0.0 && clahe_clip <= 40.0))
    return fail("clahe_clip must be in [0, 40], got " + std::to_string(clahe_clip));
  if (!(clahe_max_stddev > 0.0 && clahe_max_stddev <= 256.0))
    return fail("clahe_max_stddev must be in (0, 256], got " + std::to_string(clahe_max_stddev));
  if (min_tracked_inliers < 10)
    return fail("min_tracked_inliers must be >= 10, got " + std::to_string(min_tracked_inliers));
  if (keyframe_min_gap < 0 || keyframe_max_gap < 1 || keyframe_min_gap > keyframe_max_gap)
    return fail("keyframe gaps must satisfy 0 <= keyframe_min_gap <= keyframe_max_gap, >= 1; got " +
                std::to_string(keyframe_min_gap) + ", " + std::to_string(keyframe_max_gap));
  if (!(keyframe_tracked_ratio > 0 && keyframe_tracked_ratio < 1))
    return fail("keyframe_tracked_ratio must be in (0, 1), got " + std::to_string(keyframe_tracked_ratio));
  if (local_ba_keyframes < 2) return fail("local_ba_keyframes must be >= 2, got " + std::to_string(local_ba_keyframes));
  if (local_ba_iterations < 1)
    return fail("local_ba_iterations must be >= 1, got " + std::to_string(local_ba_iterations));
  if (mapping_neighbours < 1) return fail("mapping_neighbours must be >= 1, got " + std::to_string(mapping_neighbours));
  if (loop_consistency < 0) return fail("loop_consistency must be >= 0, got " + std::to_string(loop_consistency));
  if (loop_min_inliers < 20) return fail("loop_min_inliers must be >= 20, got " + std::to_string(loop_min_inliers));
  if (!(loop_max_correction_ratio > 0))
    return fail("loop_max_correction_ratio must be > 0, got " + std::to_string(loop_max_correction_ratio));
  if (loop_min_keyframe_gap < 5)
    return fail("loop_min_keyframe_gap must be >= 5, got " + std::to_string(loop_min_keyframe_gap));
  if (global_ba_iterations < 1)
    return fail("global_ba_iterations must be >= 1, got " + std::to_string(global_ba_iterations));
  if (relocalize_frames < 0) return fail("relocalize_frames must be >= 0, got " + std::to_string(relocalize_frames));
  if (atlas_max_maps < 0 || atlas_max_maps > 100)
    return fail("atlas_max_maps must be in [0, 100], got " + std::to_string(atlas_max_maps));
  if (!(reloc_gate_speed_factor >= 0 && std::isfinite(reloc_gate_speed_factor)))
    return fail("reloc_gate_speed_factor must be >= 0 (0: no gate), got " + std::to_string(reloc_gate_speed_factor));
  if (!(reloc_gate_min_radius >= 0 && std::isfinite(reloc_gate_min_radius)))
    return fail("reloc_gate_min_radius must be >= 0, got " + std::to_string(reloc_gate_min_radius));
  if (!(reloc_gate_deg_per_frame > 0 && reloc_gate_deg_per_frame <= 180))
    return fail("reloc_gate_deg_per_frame must be in (0, 180], got " + std::to_string(reloc_gate_deg_per_frame));
  return true;
}

const char* to_string(SlamState state) {
  switch (state) {
    case SlamState::kInitializing:
      return "initializing";
    case SlamState::kTracking:
      return "tracking";
    case SlamState::kRelocalized:
      return "relocalized";
    case SlamState::kLost:
      return "lost";
    case SlamState::kInvalidInput:
      return "invalid_input";
  }
  return "?";
}

auto MonoSlam::Impl::ToGlobal(const Eigen::Isometry3d& T_wc) const -> Eigen::Isometry3d {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = G.R * T_wc.linear();
  out.translation() = G * T_wc.translation();
  return out;
}

auto MonoSlam::Impl::CurrentTrajectory(std::size_t from) const -> std::vector<StampedPose> {
  std::vector<StampedPose> out;
  for (std::size_t i = from; i < traj.size(); ++i) {
    const TrajEntry& e = traj[i];
    const Eigen::Isometry3d T_cw = e.T_cr * map->kf(e.ref_kf).T_cw;
    out.push_back({e.stamp, ToGlobal(T_cw.inverse()), map_number});
  }
  return out;
}

auto MonoSlam::Impl::ResetForReinitialization() -> void {
  if (initialized) {
    auto t = CurrentTrajectory();
    frozen.insert(frozen.end(), t.begin(), t.end());
    // The next map continues from the last good pose at the last map's depth scale.
    // (No mapping runs while lost, so that keyframe's depth is as it was at the last good frame.)
    const double median_depth_global = G.s * map->MedianDepth(last_good_ref_kf);
    StoreCurrentMap();  // in the atlas, when worth keeping (it may be recognised and merged later)
    G = Sim3(median_depth_global, last_good_T_wc_global.linear(), last_good_T_wc_global.translation());
    ++map_number;
    ++stats.reinitializations;
    ++stats.maps;
  }
  map = std::make_unique<Map>();
  metric_stage = 0;
  map_sets_global_scale = false;
  inertial_rejection_said = false;
  dvl_rejection_said = false;
  vi_ready = false;
  vi.velocities.clear();
  db = BowDatabase();
  traj.clear();
  initialized = false;
  init_ref.reset();
  has_velocity = false;
  last_tracked = false;
  ref_kf = -1;
  local_kfs.clear();
  local_points.clear();
  recent_points.clear();
  consistent_groups.clear();
  lost_frames_in_row = 0;
  recent_steps.clear();
}

auto MonoSlam::Impl::Track(const cv::Mat& gray, double stamp) -> SlamFrameSummary {
  const auto t0 = Clock::now();
  SlamFrameSummary s;
  if (std::isfinite(stamp)) AdmitSensorData(stamp);
  if (gray.empty() || gray.type() != CV_8UC1 || gray.cols != cam.width || gray.rows != cam.height ||
      !std::isfinite(stamp)) {
    s.message = "expected a CV_8UC1 image of " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                " and a finite stamp";
    return s;
  }
  ++stats.frames;
  cur = Frame();
  cur.index = frame_index++;
  cur.stamp = stamp;
  if (opt.clahe_clip > 0.0) {
    // Only on low-contrast footage (turbid water, weak lamps), with hysteresis so that a scene
    // near the threshold does not flip between frames.
    cv::Scalar mean, stddev;
    cv::meanStdDev(gray, mean, stddev);
    if (stddev[0] < opt.clahe_max_stddev)
      clahe_on = true;
    else if (stddev[0] > 1.25 * opt.clahe_max_stddev)
      clahe_on = false;
  }
  if (clahe_on) {
    if (!clahe)
      clahe = cv::createCLAHE(opt.clahe_clip, cv::Size(std::max(2, cam.width / 40), std::max(2, cam.height / 40)));
    clahe->apply(gray, equalized);
    ExtractFeatures(equalized, initialized ? *orb : *orb_init, &cur);
  } else {
    ExtractFeatures(gray, initialized ? *orb : *orb_init, &cur);
  }
  s.features = static_cast<int>(cur.f.size());
  if (!initialized) {
    s = TryInitialize(s);
    if (initialized) {
      traj.push_back({cur.stamp, ref_kf, cur.T_cw * map->kf(ref_kf).T_cw.inverse()});
      last = cur;
      last_tracked = true;
      s.T_wc = ToGlobal(cur.T_cw.inverse());
      UpdateGoodPose();
      ++stats.tracked_frames;
    }
    s.tracking_ms = Ms(t0);
    return s;
  }
  bool ok = false;
  if (last_tracked) {
    const std::optional<Eigen::Isometry3d> imu_pose = ImuPredictedPose(cur.stamp);
    if (has_velocity || imu_pose) {
      ok = TrackWithMotionModel(imu_pose);
      if (!ok) ++stats.motion_model_misses;
    }
    if (!ok) {
      std::fill(cur.points.begin(), cur.points.end(), -1);
      ok = TrackReferenceKeyFrame();
    }
    if (ok) {
      s.inliers = TrackLocalMap();
      const bool recent_reloc = cur.index - last_reloc_frame < 10;
      ok = s.inliers >= (recent_reloc ? scaled(50) : scaled(opt.min_tracked_inliers));
    }
    s.state = ok ? SlamState::kTracking : SlamState::kLost;
  } else {
    ok = Relocalize();
    if (ok) {
      s.inliers = static_cast<int>(std::count_if(cur.points.begin(), cur.points.end(), [](int p) { return p >= 0; }));
      s.state = SlamState::kRelocalized;
      ++stats.relocalizations;
    }
  }
  if (!ok) {
    ++stats.lost_frames;
    ++lost_frames_in_row;
    s.state = SlamState::kLost;
    const bool young = map->GoodKeyFrames() <= 5;
    if (young || lost_frames_in_row > opt.relocalize_frames || !voc) {
      s.message = "tracking lost; re-initialising a new map";
      ResetForReinitialization();
      s.reinitialized = true;
    } else {
      s.message = "tracking lost; relocalising (" + std::to_string(lost_frames_in_row) + "/" +
                  std::to_string(opt.relocalize_frames) + ")" + reloc_rejection;
      last_tracked = false;
    }
    const Eigen::Isometry3d pred = has_velocity ? velocity * last.T_cw : last.T_cw;
    s.T_wc = ToGlobal(pred.inverse());
    s.tracking_ms = Ms(t0);
    return s;
  }
  lost_frames_in_row = 0;
  ++stats.tracked_frames;
  if (last_tracked && cur.index > last.index) {  // frame-to-frame motion, for the relocalisation gate
    recent_steps.push_back((CameraCentre(cur.T_cw) - CameraCentre(last.T_cw)).norm() / (cur.index - last.index));
    if (recent_steps.size() > 20) recent_steps.pop_front();
  }
  velocity = cur.T_cw * last.T_cw.inverse();
  has_velocity = last_tracked;
  s.tracking_ms = Ms(t0);
  if (NeedKeyFrame(s.inliers)) {
    const auto t1 = Clock::now();
    InsertKeyFrame();
    s.keyframe = true;
    loop_log.clear();
    s.loop_closed = LoopClosing(ref_kf);
    if (!s.loop_closed) {
      const Eigen::Isometry3d T_cr = cur.T_cw * map->kf(ref_kf).T_cw.inverse();
      s.maps_merged = MergeMaps(ref_kf);
      if (s.maps_merged) {
        cur.T_cw = T_cr * map->kf(ref_kf).T_cw;  // the weld's bundle adjustment moved the keyframe
        has_velocity = false;
      }
    }
    if (!loop_log.empty())
      s.message = (s.loop_closed ? "loop closed: " : s.maps_merged ? "maps merged: " : "loop candidates: ") + loop_log;
    if (s.loop_closed) {
      // The current frame moves with its keyframe.
      cur.T_cw = map->kf(ref_kf).T_cw;
      has_velocity = false;
    }
    if (dvl_on || inertial) {
      const std::string said = dvl_on ? TryDvlScale() : TryInertialInit();
      if (!said.empty()) s.message += (s.message.empty() ? "" : "; ") + said;
    }
    s.mapping_ms = Ms(t1);
  }
  traj.push_back({cur.stamp, ref_kf, cur.T_cw * map->kf(ref_kf).T_cw.inverse()});
  last = cur;
  last_tracked = true;
  UpdateGoodPose();
  s.T_wc = ToGlobal(cur.T_cw.inverse());
  return s;
}

auto MonoSlam::Impl::UpdateGoodPose() -> void {
  last_good_T_wc_global = ToGlobal(cur.T_cw.inverse());
  last_good_ref_kf = ref_kf;
}

MonoSlam::MonoSlam(const PinholeCamera& camera, const std::vector<double>& distortion, const MonoSlamOptions& options,
                   std::shared_ptr<const BowVocabulary> vocabulary)
    : impl_(std::make_unique<Impl>()) {
  std::string msg;
  if (!options.IsValid(&msg)) throw std::invalid_argument("MonoSlam: " + msg);
  if (!(camera.fx > 0 && camera.fy > 0 && camera.width > 0 && camera.height > 0 && std::isfinite(camera.cx) &&
        std::isfinite(camera.cy)))
    throw std::invalid_argument("MonoSlam: camera needs fx, fy > 0 and a positive image size");
  for (double d : distortion)
    if (!std::isfinite(d)) throw std::invalid_argument("MonoSlam: distortion coefficients must be finite");
  Impl& m = *impl_;
  m.opt = options;
  m.cam = camera;
  cv::eigen2cv(camera.K(), m.K);
  bool any = false;
  for (double d : distortion) any = any || d != 0.0;
  if (any) m.D = cv::Mat(distortion, true).reshape(1, 1);
  OrbOptions orb = options.orb;
  if (options.features_scale_with_area) {
    const double area_ratio = static_cast<double>(camera.width) * camera.height / (640.0 * 480.0);
    orb.features = static_cast<int>(std::lround(orb.features * std::clamp(area_ratio, 1.0, 4.0)));
  }
  m.orb = std::make_unique<OrbExtractor>(orb);
  OrbOptions init = orb;
  init.features *= options.init_orb_features_factor;
  m.orb_init = std::make_unique<OrbExtractor>(init);
  if (vocabulary && !vocabulary->empty()) m.voc = std::move(vocabulary);
  for (int l = 0; l < options.orb.levels; ++l) {
    m.scales.push_back(m.orb->scale(l));
    m.sigma2.push_back(m.orb->sigma2(l));
  }
  m.log_scale = std::log(options.orb.scale_factor);
}

MonoSlam::~MonoSlam() = default;

void MonoSlam::EnableInertial(const Eigen::Isometry3d& T_bc, const ImuNoise& noise) {
  const Eigen::Matrix3d R = T_bc.linear();
  if (!T_bc.matrix().allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      R.determinant() < 0.0)
    throw std::invalid_argument("MonoSlam::EnableInertial: T_bc must be a finite rigid transform");
  ImuPreintegration check({}, noise);  // validates the noise densities
  impl_->inertial = true;
  impl_->T_bc = T_bc;
  impl_->imu_noise = noise;
}

void MonoSlam::AddImu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  impl_->AddImu(stamp, gyro, accel);
}

void MonoSlam::EnableDvl(const Eigen::Isometry3d& T_dc) {
  const Eigen::Matrix3d R = T_dc.linear();
  if (!T_dc.matrix().allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      R.determinant() < 0.0)
    throw std::invalid_argument("MonoSlam::EnableDvl: T_dc must be a finite rigid transform");
  impl_->dvl_on = true;
  impl_->T_dc = T_dc;
}

void MonoSlam::AddDvl(double stamp, const Eigen::Vector3d& velocity, bool valid) {
  impl_->AddDvl(stamp, velocity, valid);
}

SlamFrameSummary MonoSlam::Track(const cv::Mat& gray, double stamp) {
  try {
    return impl_->Track(gray, stamp);
  } catch (const std::exception& e) {
    SlamFrameSummary s;
    s.state = SlamState::kLost;
    s.message = std::string("internal error: ") + e.what();
    return s;
  }
}

std::vector<MonoSlam::StampedPose> MonoSlam::Trajectory() const {
  std::vector<StampedPose> out = impl_->frozen;
  if (impl_->initialized) {
    const auto t = impl_->CurrentTrajectory();
    out.insert(out.end(), t.begin(), t.end());
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  return out;
}

std::vector<MonoSlam::StampedPose> MonoSlam::Trajectory(std::size_t last) const {
  if (last == 0) return Trajectory();
  const Impl& m = *impl_;
  // The earlier maps' frames and the current map's are each in time order, but may interleave
  // (a merged map brings its frames into the current one): the last `last` of each, merged.
  const std::size_t current = m.initialized ? std::min(last, m.traj.size()) : 0;
  const std::size_t earlier = std::min(last, m.frozen.size());
  std::vector<StampedPose> out(m.frozen.end() - static_cast<std::ptrdiff_t>(earlier), m.frozen.end());
  if (current > 0) {
    const auto t = m.CurrentTrajectory(m.traj.size() - current);
    out.insert(out.end(), t.begin(), t.end());
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  if (out.size() > last) out.erase(out.begin(), out.end() - static_cast<std::ptrdiff_t>(last));
  return out;
}

std::vector<MonoSlam::StampedPose> MonoSlam::KeyFrameTrajectory() const {
  std::vector<StampedPose> out;
  if (!impl_->initialized) return out;
  for (const auto& k : impl_->map->keyframes)
    if (!k->bad) out.push_back({k->stamp, impl_->ToGlobal(k->T_cw.inverse()), impl_->map_number});
  return out;
}

SlamStats MonoSlam::stats() const {
  SlamStats s = impl_->stats;
  s.keyframes = impl_->map->GoodKeyFrames();
  s.points = impl_->map->GoodPoints();
  s.metric = metric();
  return s;
}

bool MonoSlam::metric() const { return impl_->global_per_metric > 0.0; }

const Map& MonoSlam::map() const { return *impl_->map; }

}  // namespace unav::localization

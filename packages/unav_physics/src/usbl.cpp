#include "unav_physics/usbl.hpp"

#include <algorithm>
#include <cmath>

namespace unav::physics {

namespace {
constexpr double kRadPerDeg = M_PI / 180.0;
constexpr double kDefaultSoundSpeed = 1500.0;  // m/s, without a world's water
}  // namespace

Usbl::Usbl(const UsblParams& params, std::uint64_t seed) : p_(params), gen_(seed) {
  if (!(p_.sound_speed_mps > 0.0)) p_.sound_speed_mps = kDefaultSoundSpeed;
  const Eigen::Vector3d rpy = p_.transceiver_rpy_deg * kRadPerDeg;
  R_WX_ = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
              .toRotationMatrix();
  R_BX_ = R_WX_;
  x_W_ = p_.transceiver_position;  // a carried one's until set_carrier_pose()
}

void Usbl::set_carrier_pose(const Eigen::Isometry3d& X_WB) {
  if (!carried()) return;
  x_W_ = X_WB * p_.transceiver_position;
  R_WX_ = X_WB.linear() * R_BX_;
  carrier_set_ = true;
}

bool Usbl::step(double t, const Eigen::Vector3d& p_W) {
  if (!p_.enabled) return false;
  if (carried() && !carrier_set_) return false;  // not before the carrier is known (no interrogation)
  const double c = p_.sound_speed_mps;
  const Eigen::Vector3d& x = x_W_;
  const double timeout = 2.0 * p_.max_range_m / c + p_.turnaround_s;
  bool out = false;
  if (((phase_ == Phase::kInbound && !carried()) || phase_ == Phase::kTimeout) && t >= t_reply_ - 1e-12) {
    finish();
    out = true;
  } else if (phase_ == Phase::kInbound && carried()) {
    // Carried: the reply's front has travelled c (t - t1 - turnaround) from p1; it reaches the
    // moving transceiver at the gap's zero, interpolated within the step.
    const double gap = c * (t - t1_ - p_.turnaround_s) - (x - p1_).norm();
    if (gap >= 0.0) {
      const double f = gap > prev_gap_ ? -prev_gap_ / (gap - prev_gap_) : 1.0;
      t_reply_ = prev_t_ + f * (t - prev_t_);
      x2_ = prev_x_ + f * (x - prev_x_);
      finish();
      out = true;
    } else {
      prev_t_ = t;
      prev_gap_ = gap;
      prev_x_ = x;
    }
  }
  if (phase_ == Phase::kIdle) {
    if (t >= next_ping_ - 1e-9) {  // interrogate (in the step the last reply came, if due)
      t0_ = t;
      prev_t_ = t;
      prev_p_ = p_W;
      x0_ = x;
      const double r0 = (p_W - x).norm();
      prev_gap_ = -r0;
      const double share = std::min(1.0, r0 / p_.max_range_m);
      drop_ = uniform_(gen_) < p_.dropout_at_max_range * share * share;  // drawn every ping: a fixed stream
      phase_ = Phase::kOutbound;
    }
    return out;
  }
  if (phase_ != Phase::kOutbound) return out;
  // The ping's front has travelled c (t - t0); it reaches the transponder when that covers the
  // distance: the gap's zero, interpolated within the step.
  const double gap = c * (t - t0_) - (p_W - x0_).norm();
  if (gap >= 0.0) {
    const double f = gap > prev_gap_ ? -prev_gap_ / (gap - prev_gap_) : 1.0;
    const double t1 = prev_t_ + f * (t - prev_t_);
    p1_ = prev_p_ + f * (p_W - prev_p_);
    if (drop_ || c * (t1 - t0_) > p_.max_range_m) {
      phase_ = Phase::kTimeout;
      t_reply_ = t0_ + timeout;
    } else if (carried()) {
      phase_ = Phase::kInbound;  // solved step by step (the transceiver moves)
      t1_ = t1;
      prev_t_ = t;
      prev_x_ = x;
      prev_gap_ = c * (t - t1_ - p_.turnaround_s) - (x - p1_).norm();
    } else {
      phase_ = Phase::kInbound;
      t_reply_ = t1 + p_.turnaround_s + (p1_ - x).norm() / c;
    }
  } else if (c * (t - t0_) > p_.max_range_m) {  // out of range: no reply will come
    phase_ = Phase::kTimeout;
    t_reply_ = t0_ + timeout;
  } else {
    prev_t_ = t;
    prev_gap_ = gap;
    prev_p_ = p_W;
  }
  return out;
}

void Usbl::finish() {
  const std::uint64_t seq = reading_.seq + 1;
  reading_ = UsblReading{};
  reading_.seq = seq;
  reading_.stamp = t_reply_;
  reading_.ping_stamp = t0_;
  next_ping_ = std::max(t0_ + 1.0 / p_.rate_hz, t_reply_);
  const bool replied = phase_ == Phase::kInbound;
  phase_ = Phase::kIdle;
  // The same draws whether or not a reply came: one reading's outcome never shifts the next's.
  const double n_range = normal_(gen_), n_az = normal_(gen_), n_el = normal_(gen_);
  const double u_outlier = uniform_(gen_), u_error = uniform_(gen_);
  if (!replied) return;

  const Eigen::Vector3d& x = carried() ? x2_ : x_W_;  // where the reply was received
  const double c_assumed = p_.assumed_sound_speed_mps > 0.0 ? p_.assumed_sound_speed_mps : p_.sound_speed_mps;
  reading_.truth_p_W = p1_;
  reading_.truth_range_m = (p1_ - x).norm();
  double r = c_assumed * (t_reply_ - t0_ - p_.turnaround_s) / 2.0 + p_.range_stddev_m * n_range;
  if (u_outlier < p_.outlier_probability) {
    r += (2.0 * u_error - 1.0) * p_.outlier_range_m;
    reading_.outlier = true;
  }
  r = std::max(r, 0.0);
  const Eigen::Vector3d d = R_WX_.transpose() * (p1_ - x);  // the reply arrives from here
  const double sigma = p_.angle_stddev_deg * kRadPerDeg;
  const double az = std::atan2(d.y(), d.x()) + sigma * n_az;
  const double el =
      (reading_.truth_range_m > 0.0 ? std::asin(std::clamp(d.z() / d.norm(), -1.0, 1.0)) : 0.0) + sigma * n_el;
  reading_.valid = true;
  reading_.range_m = r;
  reading_.azimuth_rad = std::remainder(az, 2.0 * M_PI);
  reading_.elevation_rad = el;
  reading_.p_X = r * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  reading_.p_W = x + R_WX_ * reading_.p_X;
}

Eigen::Matrix3d usbl_fix_covariance(const UsblParams& p, const UsblReading& r) {
  // p_X = r (cos e cos a, cos e sin a, sin e): J diag(sr^2, sa^2, se^2) J^T.
  const double a = r.azimuth_rad, e = r.elevation_rad, s = p.angle_stddev_deg * kRadPerDeg;
  Eigen::Matrix3d J;
  J.col(0) << std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e);
  J.col(1) << -r.range_m * std::cos(e) * std::sin(a), r.range_m * std::cos(e) * std::cos(a), 0.0;
  J.col(2) << -r.range_m * std::sin(e) * std::cos(a), -r.range_m * std::sin(e) * std::sin(a), r.range_m * std::cos(e);
  const Eigen::Vector3d var(p.range_stddev_m * p.range_stddev_m, s * s, s * s);
  return J * var.asDiagonal() * J.transpose();
}

}  // namespace unav::physics

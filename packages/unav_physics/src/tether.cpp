#include "unav_physics/tether.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "unav_common/errors.hpp"
#include "unav_physics/seabed.hpp"

namespace unav::physics {

namespace {
constexpr double kContactHz = 10.0;       // the seabed's penalty spring: a stiff 10 Hz on a node
constexpr double kFrictionSlip = 0.01;    // m/s below which friction is viscous (regularized Coulomb)
constexpr double kStepsPerPeriod = 12.0;  // sub-steps per period of the fastest axial mode
}  // namespace

Tether::Tether(const TetherParams& params, const EnvironmentParams& env) : prm_(params), env_(env) {
  area_ = M_PI * prm_.diameter_m * prm_.diameter_m / 4.0;
  set_length(prm_.length_m);
}

void Tether::set_length(double length_m) {
  if (!(std::isfinite(length_m) && length_m > 0.0))
    throw ConfigError("tether", "length_m", std::to_string(length_m), "must be > 0 m");
  rest_ = length_m / prm_.segments;
  k_ = prm_.axial_stiffness_n / rest_;
  m_ = prm_.mass_per_m * rest_;
  const double displaced = env_.water_density * area_ * rest_;
  m_eff_ = m_ + displaced;  // added mass of a cylinder accelerating across the flow (Ca = 1)
  wet_weight_ = (m_ - displaced) * env_.gravity;
}

void Tether::reset(const Eigen::Vector3d& attach_W) {
  const Eigen::Vector3d a = prm_.anchor_position, d = attach_W - a;
  const double dist = d.norm(), total = length();
  if (total < dist - 1e-9)
    throw ConfigError("tether", "length_m", std::to_string(total),
                      "is shorter than the distance from the anchor to the vehicle (" + std::to_string(dist) + " m)");
  // A V below the chord: two straight legs of length / 2 meeting under its middle.
  Eigen::Vector3d down = Eigen::Vector3d::UnitZ();
  if (dist > 1e-9) down -= d.normalized().z() * d.normalized();
  if (down.norm() < 1e-6) down = Eigen::Vector3d::UnitX();  // a vertical chord: bulge north
  down.normalize();
  const double h = std::sqrt(std::max(0.0, 0.25 * total * total - 0.25 * dist * dist));
  const Eigen::Vector3d apex = a + 0.5 * d + h * down;
  const int n = prm_.segments;
  p_.assign(static_cast<std::size_t>(n) + 1, a);
  v_.assign(p_.size(), Eigen::Vector3d::Zero());
  f_.assign(p_.size(), Eigen::Vector3d::Zero());
  const double leg = 0.5 * total;
  for (int i = 0; i <= n; ++i) {
    const double s = total * i / n;
    p_[static_cast<std::size_t>(i)] =
        s <= leg ? a + (leg > 0 ? s / leg : 0.0) * (apex - a) : apex + (s - leg) / leg * (attach_W - apex);
  }
  p_.back() = attach_W;
}

Eigen::Vector3d Tether::segment_force(const Eigen::Vector3d& a, const Eigen::Vector3d& va, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& vb) const {
  const Eigen::Vector3d d = b - a;
  const double len = d.norm();
  if (len <= rest_ || len < 1e-12) return Eigen::Vector3d::Zero();  // slack: a cable does not push
  const Eigen::Vector3d u = d / len;
  const double c = 2.0 * prm_.damping_ratio * std::sqrt(k_ * m_eff_);
  const double tension = k_ * (len - rest_) + c * (vb - va).dot(u);
  return std::max(tension, 0.0) * u;
}

Eigen::Vector3d Tether::node_drag(std::size_t i, const Eigen::Vector3d& v, double length) const {
  // Morison drag on `length` of cable at node i moving at v: across and along the local tangent.
  const std::size_t n = p_.size() - 1;
  Eigen::Vector3d t = p_[std::min(i + 1, n)] - p_[i == 0 ? 0 : i - 1];
  t = t.norm() > 1e-12 ? Eigen::Vector3d(t.normalized()) : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d v_rel = v - current_W_;
  const Eigen::Vector3d v_t = v_rel.dot(t) * t, v_n = v_rel - v_t;
  return -0.5 * env_.water_density * prm_.diameter_m * length *
         (prm_.normal_drag_coefficient * v_n.norm() * v_n + M_PI * prm_.tangential_drag_coefficient * v_t.norm() * v_t);
}

Eigen::Vector3d Tether::force_on_vehicle_W(const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W) const {
  // The last segment's pull, and the half of it the vehicle's end carries: its wet weight and drag.
  const std::size_t n = p_.size() - 1;
  return segment_force(attach_W, attach_v_W, p_[n - 1], v_[n - 1]) + Eigen::Vector3d(0.0, 0.0, 0.5 * wet_weight_) +
         node_drag(n, attach_v_W, 0.5 * rest_);
}

Eigen::Vector3d Tether::force_on_anchor_W() const {
  return segment_force(p_[0], Eigen::Vector3d::Zero(), p_[1], v_[1]) + Eigen::Vector3d(0.0, 0.0, 0.5 * wet_weight_) +
         node_drag(0, Eigen::Vector3d::Zero(), 0.5 * rest_);
}

void Tether::step(double dt, const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W,
                  const Eigen::Vector3d& current_W, const Seabed* seabed) {
  const std::size_t n = p_.size() - 1;
  const double omega = 2.0 * std::sqrt(k_ / m_eff_);  // the chain's fastest axial mode
  const double omega_c = 2.0 * M_PI * kContactHz;
  const int subs =
      std::max(1, static_cast<int>(std::ceil(dt * std::max(omega, omega_c) * kStepsPerPeriod / (2.0 * M_PI))));
  const double h = dt / subs;
  const Eigen::Vector3d start = p_[n];
  const double k_c = m_eff_ * omega_c * omega_c, c_c = 2.0 * m_eff_ * omega_c;
  const double dn = prm_.diameter_m;
  current_W_ = current_W;
  for (int s = 1; s <= subs; ++s) {
    // The vehicle's end moves with the vehicle through the step; the anchor stays.
    for (std::size_t i = 1; i < n; ++i) {
      Eigen::Vector3d f(0.0, 0.0, wet_weight_);
      f += segment_force(p_[i], v_[i], p_[i - 1], v_[i - 1]);
      f += segment_force(p_[i], v_[i], p_[i + 1], v_[i + 1]);
      f += node_drag(i, v_[i], rest_);
      if (seabed != nullptr) {
        const double pen = p_[i].z() + 0.5 * dn - seabed->depth_at(p_[i].x(), p_[i].y());
        if (pen > 0.0) {
          const double normal = std::max(0.0, k_c * pen + c_c * v_[i].z());
          f.z() -= normal;
          const Eigen::Vector2d v_h = v_[i].head<2>();
          f.head<2>() -= prm_.seabed_friction * normal * v_h / std::max(v_h.norm(), kFrictionSlip);
        }
      }
      f_[i] = f;
    }
    for (std::size_t i = 1; i < n; ++i) {
      v_[i] += h / m_eff_ * f_[i];
      p_[i] += h * v_[i];
    }
    p_[n] = start + (attach_W - start) * (static_cast<double>(s) / subs);
    v_[n] = attach_v_W;
  }
}

}  // namespace unav::physics

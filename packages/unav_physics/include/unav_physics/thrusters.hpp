// N thrusters: first-order lag on the command, thrust per paper eq. 3, summed into a body wrench.
#pragma once

#include <vector>

#include "unav_physics/types.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::physics {

class ThrusterBank {
 public:
  explicit ThrusterBank(const std::vector<ThrusterParams>& thrusters);

  int size() const { return static_cast<int>(gain_fwd_.size()); }
  /// Advances each filter by dt (exact discretisation of u_f_dot = (u - u_f)/t_c, so a step
  /// command reaches 1 - e^-1 = 63.2% after t_c). u must have size() entries in [-1, 1].
  /// Also computes the exact mean thrust over the step (mean_thrust()): the integral of
  /// T(u_f(t)) over [0, dt] / dt with u_f(t) = u + (u_f0 - u) e^(-t/t_c), split where u_f
  /// changes sign (forward and reverse gains differ).
  void step(double dt, const ThrusterVector& u);
  void reset();

  const ThrusterVector& filtered_command() const { return u_f_; }  ///< u_f, -
  const ThrusterVector& thrust() const { return thrust_; }         ///< T_i at the end of the step, N
  /// Mean of T_i over the last step(), N (the value a fixed-step integrator must hold over it).
  const ThrusterVector& mean_thrust() const { return mean_thrust_; }
  /// Body wrench [sum n_i T_i; sum r_i x n_i T_i] at the end of the step, N / N m.
  const Vector6d& wrench_B() const { return wrench_; }
  /// Body wrench of mean_thrust(), N / N m.
  Vector6d mean_wrench_B() const { return B_ * mean_thrust_; }
  /// Exact body wrench at h in [0, dt] into the last step() (h = 0: its start, h = dt: wrench_B()).
  Vector6d wrench_at_B(double h) const;
  /// Columns [n_i; r_i x n_i]: wrench per newton of thrust (6xN), for allocation.
  const ThrusterMatrix& thruster_matrix() const { return B_; }
  /// Thrust at u = +1 per thruster, N.
  const ThrusterVector& max_forward_thrust() const { return gain_fwd_; }

 private:
  ThrusterMatrix B_;
  ThrusterVector gain_fwd_, gain_rev_, tc_, u_f_, thrust_, mean_thrust_, alpha_, decay_half_, u_f0_, u_;
  Vector6d wrench_ = Vector6d::Zero();  ///< B_ * thrust_, kept by step() and reset()
  double alpha_dt_ = -1.0;
};

}  // namespace unav::physics

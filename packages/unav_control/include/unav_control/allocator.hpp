// Thrust allocation: body wrench tau_B = [F; M] (N, N m, FRD) -> normalised thruster commands
// u_i in [-1, 1] for the physics core's thrusters (same ThrusterParams the physics server reads).
//
//   B          6xN, columns [n_i; r_i x n_i] (wrench per newton of thrust), from ThrusterBank;
//   T_i        thrust of thruster i, N, within [-T_rev_i, T_fwd_i] (asymmetric T200 curve);
//   u_i        = T_i / T_fwd_i for T_i >= 0, T_i / T_rev_i for T_i < 0 (steady-state inverse of eq. 3).
// Unsaturated: T = W^-1 B^T (B W^-1 B^T)^+ tau, the minimum of sum_i w_i (T_i / T_fwd_i)^2 with
// B T = tau (a pseudo-inverse in normalised command space, so weaker thrusters work less).
// Saturated: either uniform scaling (T -> s T, the wrench keeps its direction) or iterative
// redistribution (saturated thrusters are fixed at their limit and the residual wrench is
// reallocated over the others; falls back to uniform scaling when that cannot reach tau).
// Allocate() never throws and allocates no heap memory.
#pragma once

#include <string>
#include <vector>

#include "unav_physics/types.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::control {

using physics::ThrusterMatrix;
using physics::ThrusterVector;
using physics::Vector6d;

enum class AllocationMode {
  kPseudoInverse,  ///< weighted pseudo-inverse, uniform scaling on saturation
  kRedistributed,  ///< weighted pseudo-inverse + iterative redistribution of saturated thrusters
};
/// "pseudo_inverse" / "redistributed"; false for anything else.
bool parse_allocation_mode(const std::string& name, AllocationMode* out);
const char* to_string(AllocationMode mode);

struct AllocatorOptions {
  AllocationMode mode = AllocationMode::kRedistributed;
  /// Per-thruster weights w_i > 0 (larger = used less); empty = all 1.
  std::vector<double> thruster_weights;
  /// Redistribution passes (each fixes >= 1 saturated thruster), >= 1.
  int max_redistribution_iterations = 8;
  /// Singular values below this fraction of the largest are treated as zero (rank loss), in (0, 1).
  double rank_tolerance = 1e-9;
  /// Relative wrench error below which B T = tau counts as reproduced, > 0.
  double exactness_tolerance = 1e-9;

  /// False, with a message naming the field and value, when an option is out of range.
  bool IsValid(std::string* msg) const;
};

enum class AllocationStatus {
  kExact,          ///< B T = tau, no thruster saturated
  kScaled,         ///< saturated: T scaled uniformly by `scale` < 1, achieved = scale * tau
  kRedistributed,  ///< saturated thrusters fixed at their limits, the rest reproduce tau exactly
  kInfeasible,     ///< tau has a component the (remaining) thrusters cannot produce: least squares
  kInvalidInput,   ///< NaN/Inf in tau: u = 0
};
const char* to_string(AllocationStatus status);

struct AllocationSummary {
  AllocationStatus status = AllocationStatus::kExact;
  Vector6d requested = Vector6d::Zero();  ///< tau asked for, N / N m
  Vector6d achieved = Vector6d::Zero();   ///< B T(u) of the returned command, N / N m
  double scale = 1.0;                     ///< uniform scale applied (1 unless kScaled)
  int iterations = 0;                     ///< redistribution passes
  int saturated = 0;                      ///< thrusters with |u_i| = 1
};

/// Per-axis wrench limits, each achievable on its own (the other five components zero) by the
/// allocator's pseudo-inverse: lower(j) <= 0 <= upper(j). N (force), N m (moment), body FRD.
struct WrenchBox {
  Vector6d lower = Vector6d::Zero();
  Vector6d upper = Vector6d::Zero();
  WrenchBox Scaled(double factor) const { return {factor * lower, factor * upper}; }
  Vector6d Clamp(const Vector6d& w) const { return w.cwiseMax(lower).cwiseMin(upper); }
  bool Contains(const Vector6d& w, double tol = 0.0) const {
    return ((w - lower).array() >= -tol).all() && ((upper - w).array() >= -tol).all();
  }
};

class Allocator {
 public:
  /// Throws physics::ConfigError for invalid options, no thrusters, more than kMaxThrusters, a
  /// zero direction, or a weight count different from the thruster count.
  explicit Allocator(const std::vector<physics::ThrusterParams>& thrusters,
                     const AllocatorOptions& options = AllocatorOptions{});

  /// Commands u (resized to num_thrusters(), entries in [-1, 1], failed thrusters 0) for the
  /// body wrench tau_B. Never throws; NaN/Inf input gives u = 0 and kInvalidInput.
  AllocationSummary Allocate(const Vector6d& tau_B, ThrusterVector* u) const;

  /// Marks thruster `index` failed (its command is 0 from now on) or repaired, and recomputes the
  /// pseudo-inverse and the wrench box. Returns false for an index out of range.
  bool SetThrusterFailed(int index, bool failed);
  bool thruster_failed(int index) const { return failed_[static_cast<std::size_t>(index)]; }

  /// Steady-state wrench of command u (thrust T_i(u_i) through B), N / N m.
  Vector6d WrenchFromCommand(const ThrusterVector& u) const;
  /// What each axis can reach on its own with the working thrusters (for MPC input bounds).
  const WrenchBox& achievable_wrench_box() const { return box_; }

  int num_thrusters() const { return static_cast<int>(B_.cols()); }
  const ThrusterMatrix& thruster_matrix() const { return B_; }
  const ThrusterVector& max_forward_thrust() const { return t_fwd_; }  ///< N
  const ThrusterVector& max_reverse_thrust() const { return t_rev_; }  ///< N (positive)
  const AllocatorOptions& options() const { return options_; }

 private:
  using PinvMatrix = Eigen::Matrix<double, Eigen::Dynamic, 6, 0, physics::kMaxThrusters, 6>;
  /// Weighted pseudo-inverse over the thrusters with active(i) true (rows of the others zero);
  /// returns the numerical rank.
  int WeightedPinv(const ThrusterVector& active, PinvMatrix* P) const;
  /// Largest s in [0, 1] with s T within the thrust limits.
  double MaxScale(const ThrusterVector& T) const;
  void ToCommand(const ThrusterVector& T, ThrusterVector* u) const;
  void Recompute();

  AllocatorOptions options_;
  ThrusterMatrix B_;
  ThrusterVector t_fwd_, t_rev_, w_inv_sqrt_, active_;
  std::vector<bool> failed_;
  PinvMatrix P_;
  int rank_ = 0;
  WrenchBox box_;
};

}  // namespace unav::control

// Thrust allocation (see allocator.hpp for the formulation).
#include "unav_control/allocator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "unav_physics/thrusters.hpp"

namespace unav::control {

bool parse_allocation_mode(const std::string& name, AllocationMode* out) {
  if (name == "pseudo_inverse") {
    *out = AllocationMode::kPseudoInverse;
  } else if (name == "redistributed") {
    *out = AllocationMode::kRedistributed;
  } else {
    return false;
  }
  return true;
}

const char* to_string(AllocationMode mode) {
  return mode == AllocationMode::kPseudoInverse ? "pseudo_inverse" : "redistributed";
}

const char* to_string(AllocationStatus status) {
  switch (status) {
    case AllocationStatus::kExact: return "exact";
    case AllocationStatus::kScaled: return "scaled";
    case AllocationStatus::kRedistributed: return "redistributed";
    case AllocationStatus::kInfeasible: return "infeasible";
    case AllocationStatus::kInvalidInput: return "invalid_input";
  }
  return "unknown";
}

bool AllocatorOptions::IsValid(std::string* msg) const {
  std::ostringstream os;
  for (std::size_t i = 0; i < thruster_weights.size(); ++i) {
    if (!(std::isfinite(thruster_weights[i]) && thruster_weights[i] > 0.0)) {
      os << "thruster_weights[" << i << "] must be finite and > 0 (got " << thruster_weights[i] << ")";
      break;
    }
  }
  if (os.tellp() == 0) {
    if (max_redistribution_iterations < 1) {
      os << "max_redistribution_iterations must be >= 1 (got " << max_redistribution_iterations << ")";
    } else if (!(rank_tolerance > 0.0 && rank_tolerance < 1.0)) {
      os << "rank_tolerance must be in (0, 1) (got " << rank_tolerance << ")";
    } else if (!(exactness_tolerance > 0.0 && std::isfinite(exactness_tolerance))) {
      os << "exactness_tolerance must be finite and > 0 (got " << exactness_tolerance << ")";
    }
  }
  if (os.tellp() == 0) return true;
  if (msg != nullptr) *msg = os.str();
  return false;
}

Allocator::Allocator(const std::vector<physics::ThrusterParams>& thrusters, const AllocatorOptions& options)
    : options_(options) {
  std::string msg;
  if (!options.IsValid(&msg)) throw physics::ConfigError("allocator options: " + msg);
  if (thrusters.empty()) throw physics::ConfigError("allocator: the vehicle has no thrusters (got 0)");
  const physics::ThrusterBank bank(thrusters);  // validates directions and the count
  const int n = bank.size();
  if (!options.thruster_weights.empty() && static_cast<int>(options.thruster_weights.size()) != n) {
    throw physics::ConfigError("allocator options: thruster_weights must have one entry per thruster: |weights| = " +
                               std::to_string(options.thruster_weights.size()) +
                               ", thrusters = " + std::to_string(n));
  }
  B_ = bank.thruster_matrix();
  t_fwd_.resize(n);
  t_rev_.resize(n);
  w_inv_sqrt_.resize(n);
  active_.setOnes(n);
  failed_.assign(static_cast<std::size_t>(n), false);
  for (int i = 0; i < n; ++i) {
    const auto& t = thrusters[static_cast<std::size_t>(i)];
    t_fwd_(i) = t.max_forward_thrust();
    t_rev_(i) = t.max_reverse_thrust();
    if (!(t_fwd_(i) > 0.0 && t_rev_(i) > 0.0 && std::isfinite(t_fwd_(i)) && std::isfinite(t_rev_(i)))) {
      throw physics::ConfigError("allocator: thrusters[" + std::to_string(i) + "] (" + t.name +
                                 ") has no usable thrust (forward " + std::to_string(t_fwd_(i)) + " N, reverse " +
                                 std::to_string(t_rev_(i)) + " N)");
    }
    const double w = options.thruster_weights.empty() ? 1.0 : options.thruster_weights[static_cast<std::size_t>(i)];
    // T = D y with D = T_fwd / sqrt(w): min |y|^2 is min sum w (T / T_fwd)^2.
    w_inv_sqrt_(i) = t_fwd_(i) / std::sqrt(w);
  }
  Recompute();
}

bool Allocator::SetThrusterFailed(int index, bool failed) {
  if (index < 0 || index >= num_thrusters()) return false;
  failed_[static_cast<std::size_t>(index)] = failed;
  active_(index) = failed ? 0.0 : 1.0;
  Recompute();
  return true;
}

int Allocator::WeightedPinv(const ThrusterVector& active, PinvMatrix* P) const {
  // Bs = B D A (A = active mask); Bs^+ = Bs^T (Bs Bs^T)^+ through the 6x6 eigen-decomposition,
  // which handles rank loss (e.g. failed thrusters) without a heap-allocating SVD.
  const ThrusterVector d = w_inv_sqrt_.cwiseProduct(active);
  const ThrusterMatrix Bs = B_ * d.asDiagonal();
  const physics::Matrix6d G = Bs * Bs.transpose();
  const Eigen::SelfAdjointEigenSolver<physics::Matrix6d> eig(G);
  const Vector6d lambda = eig.eigenvalues();
  const double lmax = lambda.maxCoeff();
  const double tol = options_.rank_tolerance * options_.rank_tolerance * std::max(lmax, 0.0);
  Vector6d inv = Vector6d::Zero();
  int rank = 0;
  for (int k = 0; k < 6; ++k) {
    if (lmax > 0.0 && lambda(k) > tol) {
      inv(k) = 1.0 / lambda(k);
      ++rank;
    }
  }
  const physics::Matrix6d G_pinv = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  *P = d.asDiagonal() * (Bs.transpose() * G_pinv);
  return rank;
}

double Allocator::MaxScale(const ThrusterVector& T) const {
  double s = 1.0;
  for (int i = 0; i < T.size(); ++i) {
    if (T(i) > t_fwd_(i)) s = std::min(s, t_fwd_(i) / T(i));
    if (T(i) < -t_rev_(i)) s = std::min(s, -t_rev_(i) / T(i));
  }
  return std::max(s, 0.0);
}

void Allocator::ToCommand(const ThrusterVector& T, ThrusterVector* u) const {
  u->resize(T.size());
  for (int i = 0; i < T.size(); ++i) {
    const double v = T(i) >= 0.0 ? T(i) / t_fwd_(i) : T(i) / t_rev_(i);
    (*u)(i) = active_(i) > 0.0 ? std::clamp(v, -1.0, 1.0) : 0.0;
  }
}

Vector6d Allocator::WrenchFromCommand(const ThrusterVector& u) const {
  ThrusterVector T(u.size());
  for (int i = 0; i < u.size(); ++i) T(i) = u(i) >= 0.0 ? u(i) * t_fwd_(i) : u(i) * t_rev_(i);
  return B_ * T;
}

void Allocator::Recompute() {
  rank_ = WeightedPinv(active_, &P_);
  // Per-axis reach of the pseudo-inverse: the largest s with s * P e_j within the limits, for
  // both signs; an axis the working thrusters cannot produce gets 0.
  for (int j = 0; j < 6; ++j) {
    const ThrusterVector T = P_.col(j);
    const bool reachable = (B_ * T - Vector6d::Unit(j)).norm() < 1e-6;
    if (!reachable) {
      box_.upper(j) = box_.lower(j) = 0.0;
      continue;
    }
    const double big = 1e9;
    box_.upper(j) = big * MaxScale(big * T);
    box_.lower(j) = -big * MaxScale(-big * T);
  }
}

AllocationSummary Allocator::Allocate(const Vector6d& tau, ThrusterVector* u) const {
  AllocationSummary s;
  s.requested = tau;
  const int n = num_thrusters();
  if (!tau.allFinite()) {
    u->setZero(n);
    s.status = AllocationStatus::kInvalidInput;
    s.scale = 0.0;
    return s;
  }
  const double tol = options_.exactness_tolerance * std::max(1.0, tau.norm());
  ThrusterVector T = P_ * tau;
  const bool in_range = (B_ * T - tau).norm() <= tol;
  const double scale = MaxScale(T);
  if (scale >= 1.0) {
    ToCommand(T, u);
    s.status = in_range ? AllocationStatus::kExact : AllocationStatus::kInfeasible;
    s.achieved = WrenchFromCommand(*u);
    return s;
  }

  if (options_.mode == AllocationMode::kRedistributed && in_range) {
    ThrusterVector free = active_;
    ThrusterVector T_fixed = ThrusterVector::Zero(n);
    Vector6d tau_rem = tau;
    PinvMatrix P;
    for (int it = 1; it <= options_.max_redistribution_iterations; ++it) {
      s.iterations = it;
      // Saturated thrusters are clamped at their limit and leave the free set.
      int newly_fixed = 0;
      const ThrusterVector Tf = (it == 1 ? P_ : P) * tau_rem;
      for (int i = 0; i < n; ++i) {
        if (free(i) == 0.0) continue;
        if (Tf(i) > t_fwd_(i) || Tf(i) < -t_rev_(i)) {
          T_fixed(i) = std::clamp(Tf(i), -t_rev_(i), t_fwd_(i));
          free(i) = 0.0;
          ++newly_fixed;
        }
      }
      if (newly_fixed == 0) {
        if ((B_ * (T_fixed + Tf) - tau).norm() <= tol) {
          ToCommand(T_fixed + Tf, u);
          s.status = AllocationStatus::kRedistributed;
          s.achieved = WrenchFromCommand(*u);
          s.saturated = static_cast<int>((u->array().abs() >= 1.0 - 1e-12).count());
          return s;
        }
        break;
      }
      tau_rem = tau - B_ * T_fixed;
      if (free.sum() == 0.0) break;
      WeightedPinv(free, &P);
      if ((B_ * (P * tau_rem) - tau_rem).norm() > tol) break;  // the free thrusters cannot finish the job
    }
  }
  // Uniform scaling: the achieved wrench keeps tau's direction.
  T *= scale;
  ToCommand(T, u);
  s.status = in_range ? AllocationStatus::kScaled : AllocationStatus::kInfeasible;
  s.scale = scale;
  s.achieved = WrenchFromCommand(*u);
  s.saturated = static_cast<int>((u->array().abs() >= 1.0 - 1e-12).count());
  return s;
}

}  // namespace unav::control

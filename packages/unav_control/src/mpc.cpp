// Nonlinear MPC (see mpc.hpp). The only translation unit that includes Ceres.
#include "unav_control/mpc.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <sstream>

#include <ceres/ceres.h>

#include "unav_physics/dynamics.hpp"

namespace unav::control {

using physics::RigidBodyState;
using Tangent = Eigen::Matrix<double, 12, 1>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;

PoseSetpoint PoseSetpoint::FromPositionYaw(const Eigen::Vector3d& p_W, double yaw) {
  PoseSetpoint s;
  s.p_W = p_W;
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return s;
}

const char* to_string(MpcStatus status) {
  // In the enum's order (mpc.hpp).
  static constexpr std::array<const char*, 7> kNames = {"converged",      "max_iterations", "time_limit",
                                                        "solver_failure", "invalid_state",  "invalid_setpoint",
                                                        "invalid_time"};
  const auto i = static_cast<std::size_t>(status);
  return i < kNames.size() ? kNames[i] : "unknown";
}

namespace {

template <typename Derived>
std::string text(const Eigen::MatrixBase<Derived>& v) {
  std::ostringstream os;
  os << "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) os << (i ? ", " : "") << v(i);
  os << "]";
  return os.str();
}

/// Rotation vector of a unit quaternion (shortest way), rad.
Eigen::Vector3d log_q(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in;
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  if (s < 1e-9) return 2.0 * v / q.w();
  return (2.0 * std::atan2(s, q.w()) / s) * v;
}

/// Inverse right Jacobian of SO(3): Log(Exp(phi) Exp(d)) ~ phi + Jr^-1(phi) d.
Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d S = physics::skew(phi);
  if (th < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * S;
  const double c = 1.0 / (th * th) - (1.0 + std::cos(th)) / (2.0 * th * std::sin(th));
  return Eigen::Matrix3d::Identity() + 0.5 * S + c * S * S;
}

bool finite_state(const RigidBodyState& x) {
  return x.p_WB_W.allFinite() && x.q_WB.coeffs().allFinite() && x.v_WB_B.allFinite() && x.w_WB_B.allFinite();
}

constexpr int kMaxControlBlocks = 20;
constexpr double kUnitTolerance = 1e-3;  // |q| may differ from 1 by float32 round-trips, not more

}  // namespace

bool MpcOptions::IsValid(std::string* msg) const {
  std::ostringstream os;
  if (horizon_steps < 1) {
    os << "horizon_steps must be >= 1 (got " << horizon_steps << ")";
  } else if (!(std::isfinite(dt) && dt > 0.0)) {
    os << "dt must be finite and > 0 s (got " << dt << ")";
  } else if (control_blocks < 1 || control_blocks > std::min(horizon_steps, kMaxControlBlocks)) {
    os << "control_blocks must be in [1, min(horizon_steps = " << horizon_steps << ", " << kMaxControlBlocks
       << ")] (got " << control_blocks << ")";
  } else if (!state_weights.allFinite() || (state_weights.array() < 0.0).any()) {
    os << "state_weights must be finite and >= 0 (a positive semi-definite diagonal) (got " << text(state_weights)
       << ")";
  } else if (!(state_weights.array() > 0.0).any()) {
    os << "state_weights must not all be zero (got " << text(state_weights) << ")";
  } else if (!(std::isfinite(terminal_weight_scale) && terminal_weight_scale >= 0.0)) {
    os << "terminal_weight_scale must be finite and >= 0 (got " << terminal_weight_scale << ")";
  } else if (!input_weights.allFinite() || (input_weights.array() < 0.0).any()) {
    os << "input_weights must be finite and >= 0 (a positive semi-definite diagonal) (got " << text(input_weights)
       << ")";
  } else if (!input_rate_weights.allFinite() || (input_rate_weights.array() < 0.0).any()) {
    os << "input_rate_weights must be finite and >= 0 (a positive semi-definite diagonal) (got "
       << text(input_rate_weights) << ")";
  } else if (!input_bounds.lower.allFinite() || !input_bounds.upper.allFinite() ||
             (input_bounds.lower.array() > input_bounds.upper.array()).any()) {
    os << "input_bounds must be finite with lower <= upper on every axis (got lower = " << text(input_bounds.lower)
       << ", upper = " << text(input_bounds.upper) << ")";
  } else if ((input_bounds.lower.array() > 0.0).any() || (input_bounds.upper.array() < 0.0).any()) {
    os << "input_bounds must contain the zero wrench (got lower = " << text(input_bounds.lower)
       << ", upper = " << text(input_bounds.upper) << ")";
  } else if (!(std::isfinite(actuator_time_constant) && actuator_time_constant >= 0.0)) {
    os << "actuator_time_constant must be finite and >= 0 s (got " << actuator_time_constant << ")";
  } else if (!(disturbance_gain >= 0.0 && disturbance_gain <= 1.0)) {
    os << "disturbance_gain must be in [0, 1] (got " << disturbance_gain << ")";
  } else if (!(std::isfinite(disturbance_limit_fraction) && disturbance_limit_fraction >= 0.0)) {
    os << "disturbance_limit_fraction must be finite and >= 0 (got " << disturbance_limit_fraction << ")";
  } else if (max_iterations < 1) {
    os << "max_iterations must be >= 1 (got " << max_iterations << ")";
  } else if (!(std::isfinite(max_solve_time_ms) && max_solve_time_ms >= 0.0)) {
    os << "max_solve_time_ms must be finite and >= 0 (0 = iterations only; got " << max_solve_time_ms << ")";
  } else if (!(std::isfinite(function_tolerance) && function_tolerance > 0.0)) {
    os << "function_tolerance must be finite and > 0 (got " << function_tolerance << ")";
  }
  if (os.tellp() == 0) return true;
  if (msg != nullptr) *msg = os.str();
  return false;
}

// ---------------------------------------------------------------------------------------------

struct Mpc::Impl {
  Impl(const physics::VehicleParams& model, const MpcOptions& o, const physics::EnvironmentParams& env);

  // Configuration.
  MpcOptions opt;
  physics::VehicleDynamics dyn;
  Eigen::Index N = 0, nb = 0;      // horizon steps, control blocks (Eigen::Index: offsets in 64 bits)
  std::vector<int> block_of_step;  // N
  std::vector<int> block_len;      // nb
  std::vector<double> lag_f0;      // N: coefficient of tau_f0 in the mean wrench of stage k
  std::vector<double> lag_u;       // N x nb: coefficient of block b in the mean wrench of stage k
  Vector12d sqrt_q, sqrt_q_terminal;
  Vector6d sqrt_r, sqrt_rd;
  double lag_a = 0.0, lag_m = 0.0;  // per model step: decay, mean fraction of the old value

  // Per-solve data read by the cost function.
  RigidBodyState x0;
  Eigen::Vector3d p_ref = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ref = Eigen::Quaterniond::Identity();
  Vector6d tau_ss = Vector6d::Zero();
  Vector6d tau_prev = Vector6d::Zero();  // previous command (rate cost)
  Vector6d tau_f0 = Vector6d::Zero();    // lagged wrench now (model state)
  Vector6d d_hat = Vector6d::Zero();

  // Controller memory.
  bool has_plan = false, has_prev_state = false, has_time = false;
  double t_prev = 0.0;
  RigidBodyState x_prev;
  Vector6d applied = Vector6d::Zero();
  std::vector<double> params, prev_params;
  // Sensitivities d x_k / d params (scratch, fixed capacity: no heap in the loop).
  Eigen::Matrix<double, 12, Eigen::Dynamic, 0, 12, 6 * kMaxControlBlocks> S;

  ceres::Problem problem;
  ceres::Solver::Options solver_options;

  RigidBodyState Step(const RigidBodyState& x, const Vector6d& tau, double h) const {
    RigidBodyState y = x;
    physics::DynamicsInputs in;
    in.tau_B = tau;
    dyn.step(y, h, in, physics::Integrator::kVelocityVerlet);
    return y;
  }
  Vector6d StageWrench(const double* U, int k) const {
    Vector6d w = lag_f0[static_cast<std::size_t>(k)] * tau_f0 + d_hat;
    for (Eigen::Index b = 0; b < nb; ++b) {
      const double g = lag_u[static_cast<std::size_t>(k * nb + b)];
      if (g != 0.0) w += g * Eigen::Map<const Vector6d>(U + 6 * b);
    }
    return w;
  }
  Tangent Error(const RigidBodyState& x) const {
    Tangent e;
    e.segment<3>(0) = x.p_WB_W - p_ref;
    e.segment<3>(3) = log_q(q_ref.conjugate() * x.q_WB);
    e.segment<3>(6) = x.v_WB_B;
    e.segment<3>(9) = x.w_WB_B;
    return e;
  }
  bool Evaluate(const double* U, double* residuals, double* jacobian);
  void ApplyBounds();
  Vector6d SafeWrench(int shift) const;
  struct Cost;
};

struct Mpc::Impl::Cost final : public ceres::CostFunction {
  Cost(Mpc::Impl* impl, int num_residuals, int num_params) : impl_(impl) {
    set_num_residuals(num_residuals);
    mutable_parameter_block_sizes()->push_back(num_params);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    return impl_->Evaluate(parameters[0], residuals, jacobians != nullptr ? jacobians[0] : nullptr);
  }
  Mpc::Impl* impl_;  // not owned; outlives the Problem that owns this
};

bool Mpc::Impl::Evaluate(const double* U, double* residuals, double* jacobian) {
  const int np = 6 * nb;
  const int nr = 12 * N + 12 * nb;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Map<RowMajor> J(jacobian, jacobian != nullptr ? nr : 0, jacobian != nullptr ? np : 0);
  if (jacobian != nullptr) {
    J.setZero();
    S.setZero();
  }
  RigidBodyState x = x0;
  int row = 0;
  for (Eigen::Index k = 0; k < N; ++k) {
    const Vector6d w = StageWrench(U, k);
    // The model step and, when Ceres wants the Jacobian, its analytic derivatives in tangent
    // coordinates (x + d: p + dp, q Exp(dtheta), nu + dnu): the Gauss-Newton model is the
    // rollout's own linearisation (it was forward differences of the step, 15 more steps a stage:
    // the same to ~1e-6, and 1.55x the CPU of a solve: bench_control replay p50 0.355 -> 0.229 ms).
    RigidBodyState x1 = x;
    Matrix12d A;
    Eigen::Matrix<double, 12, 6> Bk;
    dyn.verlet_step_jacobians(x1, opt.dt, w, jacobian != nullptr ? &A : nullptr, jacobian != nullptr ? &Bk : nullptr);
    if (jacobian != nullptr) {
      // Only the blocks up to this stage's have non-zero sensitivities so far.
      const Eigen::Index bk = block_of_step[static_cast<std::size_t>(k)];
      const Eigen::Index nc = 6 * (bk + 1);
      S.leftCols(nc) = (A * S.leftCols(nc)).eval();
      for (Eigen::Index b = 0; b <= bk; ++b) {
        const double g = lag_u[static_cast<std::size_t>(k * nb + b)];
        if (g != 0.0) S.middleCols<6>(6 * b) += g * Bk;
      }
    }
    x = x1;
    const Tangent e = Error(x);
    const Vector12d& sq = (k == N - 1) ? sqrt_q_terminal : sqrt_q;
    Eigen::Map<Vector12d>(residuals + row) = sq.cwiseProduct(e);
    if (jacobian != nullptr) {
      const int nc = 6 * (block_of_step[static_cast<std::size_t>(k)] + 1);
      const Eigen::Matrix3d Jr_inv = right_jacobian_inverse(e.segment<3>(3));
      J.block(row, 0, 12, nc) = sq.asDiagonal() * S.leftCols(nc);
      J.block(row + 3, 0, 3, nc) = sq.segment<3>(3).asDiagonal() * (Jr_inv * S.middleRows<3>(3).leftCols(nc));
    }
    row += 12;
  }
  for (Eigen::Index b = 0; b < nb; ++b) {
    const Eigen::Map<const Vector6d> u(U + 6 * b);
    const Vector6d sr = std::sqrt(static_cast<double>(block_len[static_cast<std::size_t>(b)])) * sqrt_r;
    Eigen::Map<Vector6d>(residuals + row) = sr.cwiseProduct(u - tau_ss);
    if (jacobian != nullptr) {
      for (int j = 0; j < 6; ++j) J(row + j, 6 * b + j) = sr(j);
    }
    row += 6;
  }
  for (Eigen::Index b = 0; b < nb; ++b) {
    const Eigen::Map<const Vector6d> u(U + 6 * b);
    const Vector6d u_before = b == 0 ? tau_prev : Vector6d(Eigen::Map<const Vector6d>(U + 6 * (b - 1)));
    Eigen::Map<Vector6d>(residuals + row) = sqrt_rd.cwiseProduct(u - u_before);
    if (jacobian != nullptr) {
      for (int j = 0; j < 6; ++j) {
        J(row + j, 6 * b + j) = sqrt_rd(j);
        if (b > 0) J(row + j, 6 * (b - 1) + j) = -sqrt_rd(j);
      }
    }
    row += 6;
  }
  return true;  // Ceres checks the values itself
}

namespace {
ceres::Problem::Options problem_options() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  o.enable_fast_removal = false;
  return o;
}
}  // namespace

Mpc::Impl::Impl(const physics::VehicleParams& model, const MpcOptions& o, const physics::EnvironmentParams& env)
    : opt(o), dyn(model, env), problem(problem_options()) {
  N = o.horizon_steps;
  nb = o.control_blocks;
  // Equal blocks; the remainder goes to the later (less important) blocks.
  block_len.assign(static_cast<std::size_t>(nb), N / nb);
  for (int r = 0; r < N % nb; ++r) ++block_len[static_cast<std::size_t>(nb - 1 - r)];
  for (Eigen::Index b = 0; b < nb; ++b) {
    for (int i = 0; i < block_len[static_cast<std::size_t>(b)]; ++i) block_of_step.push_back(b);
  }
  // Exact first-order lag under a zero-order-hold command c over a step h:
  //   f_{k+1} = a f_k + (1 - a) c, mean over the step = m f_k + (1 - m) c,
  //   a = exp(-h / tc), m = tc / h (1 - a).  tc = 0: no lag (a = m = 0).
  if (o.actuator_time_constant > 0.0) {
    lag_a = std::exp(-o.dt / o.actuator_time_constant);
    lag_m = o.actuator_time_constant / o.dt * (1.0 - lag_a);
  }
  lag_f0.assign(static_cast<std::size_t>(N), 0.0);
  lag_u.assign(static_cast<std::size_t>(N * nb), 0.0);
  std::vector<double> f_u(static_cast<std::size_t>(nb), 0.0);  // f_k = f0c tau_f0 + sum f_u[b] U_b
  double f0c = 1.0;
  for (Eigen::Index k = 0; k < N; ++k) {
    const int bk = block_of_step[static_cast<std::size_t>(k)];
    lag_f0[static_cast<std::size_t>(k)] = lag_m * f0c;
    for (Eigen::Index b = 0; b < nb; ++b) {
      lag_u[static_cast<std::size_t>(k * nb + b)] =
          lag_m * f_u[static_cast<std::size_t>(b)] + (b == bk ? 1.0 - lag_m : 0.0);
      f_u[static_cast<std::size_t>(b)] = lag_a * f_u[static_cast<std::size_t>(b)] + (b == bk ? 1.0 - lag_a : 0.0);
    }
    f0c *= lag_a;
  }
  sqrt_q = o.state_weights.cwiseSqrt();
  sqrt_q_terminal = std::sqrt(o.terminal_weight_scale) * sqrt_q;
  sqrt_r = o.input_weights.cwiseSqrt();
  sqrt_rd = o.input_rate_weights.cwiseSqrt();
  S.setZero(12, 6 * nb);

  params.assign(static_cast<std::size_t>(6 * nb), 0.0);
  prev_params = params;
  problem.AddResidualBlock(new Cost(this, 12 * N + 12 * nb, 6 * nb), nullptr, params.data());
  ApplyBounds();

  auto& so = solver_options;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;  // DOGLEG misbehaves with bounds
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;        // 6 nb unknowns: tiny normal equations
  // With bounds, Ceres' trust-region minimizer line-searches along the projected step and
  // evaluates Jacobians at every trial (measured: ~9 Jacobians per solve for ~3 iterations).
  // Plain projected steps (the trust region still accepts/rejects them) are much cheaper.
  so.max_num_line_search_step_size_iterations = 0;
  so.max_num_iterations = o.max_iterations;
  // 0 = no wall-clock budget: the solve is bounded by max_iterations only, so the same inputs
  // give the same wrench on any machine (lockstep runs repeat bit for bit).
  if (o.max_solve_time_ms > 0.0) so.max_solver_time_in_seconds = o.max_solve_time_ms * 1e-3;
  so.function_tolerance = o.function_tolerance;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
}

void Mpc::Impl::ApplyBounds() {
  for (Eigen::Index b = 0; b < nb; ++b) {
    for (int j = 0; j < 6; ++j) {
      double lo = opt.input_bounds.lower(j), hi = opt.input_bounds.upper(j);
      if (hi - lo < 1e-9) {  // a fixed axis (e.g. unreachable after a failure): Ceres wants lo < hi
        lo -= 1e-9;
        hi += 1e-9;
      }
      problem.SetParameterLowerBound(params.data(), 6 * b + j, lo);
      problem.SetParameterUpperBound(params.data(), 6 * b + j, hi);
    }
  }
}

Vector6d Mpc::Impl::SafeWrench(int shift) const {
  if (!has_plan) return Vector6d::Zero();
  const Eigen::Index k = std::clamp<Eigen::Index>(shift, 0, N - 1);
  const Vector6d w = Eigen::Map<const Vector6d>(
      prev_params.data() + 6 * static_cast<Eigen::Index>(block_of_step[static_cast<std::size_t>(k)]));
  return w.allFinite() ? opt.input_bounds.Clamp(w) : Vector6d::Zero();
}

// ---------------------------------------------------------------------------------------------

Mpc::Mpc(const physics::VehicleParams& model, const MpcOptions& options, const physics::EnvironmentParams& env) {
  std::string msg;
  if (!options.IsValid(&msg)) throw physics::ConfigError("mpc options: " + msg);
  impl_ = std::make_unique<Impl>(model, options, env);
}

Mpc::~Mpc() = default;

const MpcOptions& Mpc::options() const { return impl_->opt; }
const Vector6d& Mpc::disturbance_estimate() const { return impl_->d_hat; }
void Mpc::SetAppliedWrench(const Vector6d& wrench_B) {
  if (wrench_B.allFinite()) impl_->applied = wrench_B;
}

void Mpc::Reset() {
  Impl& m = *impl_;
  m.has_plan = m.has_prev_state = m.has_time = false;
  m.d_hat.setZero();
  m.tau_f0.setZero();
  m.tau_prev.setZero();
  m.applied.setZero();
  std::fill(m.params.begin(), m.params.end(), 0.0);
  m.prev_params = m.params;
}

std::vector<Vector6d> Mpc::planned_wrenches() const {
  std::vector<Vector6d> out;
  for (Eigen::Index b = 0; b < impl_->nb; ++b)
    out.emplace_back(Eigen::Map<const Vector6d>(impl_->prev_params.data() + 6 * b));
  return out;
}

std::vector<physics::RigidBodyState> Mpc::predicted_states() const {
  const Impl& m = *impl_;
  std::vector<physics::RigidBodyState> out;
  RigidBodyState x = m.x0;
  for (Eigen::Index k = 0; k < m.N; ++k) {
    x = m.Step(x, m.StageWrench(m.prev_params.data(), k), m.opt.dt);
    out.push_back(x);
  }
  return out;
}

MpcSummary Mpc::Solve(const RigidBodyState& x_in, const PoseSetpoint& sp, double t, Vector6d* wrench_B) {
  const auto t_start = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  MpcSummary s;
  auto elapsed_ms = [&] {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_start).count();
  };
  // Time since the last solve: shifts the plan and advances the actuator model.
  double dt_since = 0.0;
  if (std::isfinite(t) && m.has_time && t > m.t_prev) dt_since = t - m.t_prev;
  const int shift = static_cast<int>(std::lround(dt_since / m.opt.dt));
  auto fail = [&](MpcStatus status, std::string message) {
    *wrench_B = m.SafeWrench(shift);
    s.status = status;
    s.message = std::move(message);
    m.has_prev_state = false;  // no trustworthy state to predict from
    if (std::isfinite(t)) {
      m.t_prev = t;
      m.has_time = true;
    }
    m.applied = *wrench_B;
    s.solve_time_ms = elapsed_ms();
    return s;
  };
  if (!std::isfinite(t)) return fail(MpcStatus::kInvalidTime, "t is not finite");
  if (!finite_state(x_in) || std::abs(x_in.q_WB.norm() - 1.0) > kUnitTolerance) {
    std::ostringstream os;
    os << "state rejected: p = " << text(x_in.p_WB_W) << ", q (xyzw) = " << text(x_in.q_WB.coeffs())
       << " (|q| = " << x_in.q_WB.norm() << "), v = " << text(x_in.v_WB_B) << ", w = " << text(x_in.w_WB_B);
    return fail(MpcStatus::kInvalidState, os.str());
  }
  if (!sp.p_W.allFinite() || !sp.q_WB.coeffs().allFinite() || std::abs(sp.q_WB.norm() - 1.0) > kUnitTolerance) {
    std::ostringstream os;
    os << "setpoint rejected: p = " << text(sp.p_W) << ", q (xyzw) = " << text(sp.q_WB.coeffs())
       << " (|q| = " << sp.q_WB.norm() << ", must be a finite unit quaternion)";
    return fail(MpcStatus::kInvalidSetpoint, os.str());
  }
  RigidBodyState x = x_in;
  x.q_WB.normalize();

  // Actuator model and disturbance estimate from the prediction since the last solve.
  if (dt_since > 0.0) {
    const int n_sub = std::max(1, static_cast<int>(std::ceil(dt_since / m.opt.dt - 1e-9)));
    const double h = dt_since / n_sub;
    double a = 0.0, mf = 0.0;
    if (m.opt.actuator_time_constant > 0.0) {
      a = std::exp(-h / m.opt.actuator_time_constant);
      mf = m.opt.actuator_time_constant / h * (1.0 - a);
    }
    RigidBodyState xp = m.x_prev;
    Vector6d f = m.tau_f0;
    for (int i = 0; i < n_sub; ++i) {
      if (m.has_prev_state) xp = m.Step(xp, mf * f + (1.0 - mf) * m.applied + m.d_hat, h);
      f = a * f + (1.0 - a) * m.applied;
    }
    m.tau_f0 = f;
    if (m.has_prev_state && m.opt.disturbance_gain > 0.0 && dt_since <= 10.0 * m.opt.dt) {
      const Vector6d e_nu = x.nu() - xp.nu();
      const Vector6d d_new = m.d_hat + m.opt.disturbance_gain * (m.dyn.M() * e_nu) / dt_since;
      if (d_new.allFinite()) {
        const double fr = m.opt.disturbance_limit_fraction;
        // tau_ss = g - d_hat must stay inside the bounds: d_hat in [-upper, -lower] (scaled).
        m.d_hat = d_new.cwiseMax(-fr * m.opt.input_bounds.upper).cwiseMin(-fr * m.opt.input_bounds.lower);
      }
    }
  }
  m.x_prev = x;
  m.has_prev_state = true;
  m.t_prev = t;
  m.has_time = true;

  // Problem data for this solve.
  m.x0 = x;
  m.p_ref = sp.p_W;
  m.q_ref = sp.q_WB.normalized();
  RigidBodyState x_ref;
  x_ref.p_WB_W = m.p_ref;
  x_ref.q_WB = m.q_ref;
  m.tau_ss = m.opt.input_bounds.Clamp(m.dyn.restoring(x_ref) - m.d_hat);
  m.tau_prev = m.applied;

  // Warm start: the previous plan shifted by the elapsed model steps (last block held).
  for (Eigen::Index b = 0, k0 = 0; b < m.nb; k0 += m.block_len[static_cast<std::size_t>(b)], ++b) {
    Vector6d w = m.tau_ss;
    if (m.has_plan) {
      const Eigen::Index k = std::min<Eigen::Index>(k0 + shift, m.N - 1);
      w = Eigen::Map<const Vector6d>(m.prev_params.data() +
                                     6 * static_cast<Eigen::Index>(m.block_of_step[static_cast<std::size_t>(k)]));
    }
    Eigen::Map<Vector6d>(m.params.data() + 6 * b) = m.opt.input_bounds.Clamp(w);
  }

  ceres::Solver::Summary cs;
  ceres::Solve(m.solver_options, &m.problem, &cs);
  s.iterations = std::max(0, static_cast<int>(cs.iterations.size()) - 1);  // minus Ceres' iteration 0
  s.initial_cost = cs.initial_cost;
  s.cost = cs.final_cost;
  const Vector6d first = Eigen::Map<const Vector6d>(m.params.data());
  const bool usable = (cs.termination_type == ceres::CONVERGENCE || cs.termination_type == ceres::NO_CONVERGENCE) &&
                      first.allFinite() && std::isfinite(cs.final_cost);
  if (!usable) {
    // Keep the old plan for the safe wrench; the next warm start restarts from it.
    std::string msg = "ceres: " + cs.message;
    Eigen::Map<Eigen::VectorXd>(m.params.data(), static_cast<Eigen::Index>(m.params.size())) =
        Eigen::Map<Eigen::VectorXd>(m.prev_params.data(), static_cast<Eigen::Index>(m.prev_params.size()));
    auto out = fail(MpcStatus::kSolverFailure, msg);
    m.has_prev_state = true;  // the state itself was fine
    return out;
  }
  if (cs.termination_type == ceres::CONVERGENCE) {
    s.status = MpcStatus::kConverged;
  } else if (m.opt.max_solve_time_ms > 0.0 && cs.total_time_in_seconds >= m.solver_options.max_solver_time_in_seconds) {
    s.status = MpcStatus::kTimeLimit;
  } else {
    s.status = MpcStatus::kMaxIterations;
  }
  m.prev_params = m.params;
  m.has_plan = true;
  *wrench_B = m.opt.input_bounds.Clamp(first);
  m.applied = *wrench_B;
  s.solve_time_ms = elapsed_ms();
  if (m.opt.max_solve_time_ms > 0.0 && s.solve_time_ms > m.opt.max_solve_time_ms && s.status == MpcStatus::kConverged)
    s.status = MpcStatus::kTimeLimit;
  return s;
}

}  // namespace unav::control

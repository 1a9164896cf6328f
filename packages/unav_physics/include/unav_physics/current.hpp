// Water current models (velocity of the water in NED, m/s), configured per world.
// The analytic models are pure functions of time; the Gauss-Markov model has state advanced by
// step() with its own seeded generator (same seed, same sequence).
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_physics/types.hpp"

namespace unav::physics {

class CurrentModel {
 public:
  virtual ~CurrentModel() = default;
  /// Water velocity in NED at simulated time t (s), m/s.
  virtual Eigen::Vector3d velocity_W(double t) const = 0;
  /// Time derivative of velocity_W, m/s^2 (used for nu_c_dot; 0 for piecewise-constant models).
  virtual Eigen::Vector3d acceleration_W(double /*t*/) const { return Eigen::Vector3d::Zero(); }
  /// Advances internal state from t to t + dt (s); no-op for the analytic models.
  virtual void step(double /*t*/, double /*dt*/) {}
};

/// v_c(t) = v.
class ConstantCurrent final : public CurrentModel {
 public:
  explicit ConstantCurrent(const Eigen::Vector3d& velocity_W = Eigen::Vector3d::Zero()) : v_W_(velocity_W) {}
  Eigen::Vector3d velocity_W(double) const override { return v_W_; }

 private:
  Eigen::Vector3d v_W_;
};

/// One sine per axis: v_c(t) = mean + amplitude .* sin(2 pi f t + phase).
class SinusoidalCurrent final : public CurrentModel {
 public:
  /// mean, amplitude in m/s (NED); frequency in Hz (> 0); phase in rad.
  SinusoidalCurrent(const Eigen::Vector3d& mean_W, const Eigen::Vector3d& amplitude_W, double frequency_hz,
                    double phase_rad = 0.0);
  Eigen::Vector3d velocity_W(double t) const override;
  Eigen::Vector3d acceleration_W(double t) const override;

 private:
  Eigen::Vector3d mean_W_, amplitude_W_;
  double omega_, phase_;
};

/// v_c(t) = mean + sum_k amplitude_k .* sin(2 pi f_k t + phase_k) (waves / tidal mixtures).
class SumOfSinesCurrent final : public CurrentModel {
 public:
  struct Component {
    Eigen::Vector3d amplitude_W = Eigen::Vector3d::Zero();  ///< m/s, NED
    double frequency_hz = 0.1;                              ///< Hz, > 0
    double phase_rad = 0.0;                                 ///< rad
  };
  SumOfSinesCurrent(const Eigen::Vector3d& mean_W, std::vector<Component> components);
  Eigen::Vector3d velocity_W(double t) const override;
  Eigen::Vector3d acceleration_W(double t) const override;

 private:
  Eigen::Vector3d mean_W_;
  std::vector<Component> components_;
};

/// First-order Gauss-Markov process per axis: dv = -(v - mean)/T dt + noise, discretised
/// exactly: v_{k+1} = mean + e (v_k - mean) + sigma sqrt(1 - e^2) n_k, e = exp(-dt/T), where
/// sigma is the stationary standard deviation (m/s) and n_k ~ N(0, 1) from a seeded mt19937_64.
/// velocity_W(t) returns the current sample (held over a step).
class GaussMarkovCurrent final : public CurrentModel {
 public:
  GaussMarkovCurrent(const Eigen::Vector3d& mean_W, const Eigen::Vector3d& stddev_W, double time_constant_s,
                     std::uint64_t seed, const Eigen::Vector3d& initial_W);
  Eigen::Vector3d velocity_W(double) const override { return v_W_; }
  void step(double t, double dt) override;

 private:
  Eigen::Vector3d mean_W_, stddev_W_, v_W_;
  double time_constant_s_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

/// Builds a current from a YAML map (examples in config/water/currents/):
///   type: constant | sinusoidal | sum_of_sines | gauss_markov, plus that model's keys.
/// Throws ConfigError naming `source`, the key, the value and the rule.
std::unique_ptr<CurrentModel> make_current(const YAML::Node& node, const std::string& source,
                                           const std::string& key = "current");
/// Loads a YAML file whose top level is the current map (or has a `current:` key).
std::unique_ptr<CurrentModel> load_current(const std::string& yaml_path);

}  // namespace unav::physics

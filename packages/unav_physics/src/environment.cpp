// Water currents, seabed height fields and environment checks (no YAML here: see config.cpp).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "unav_physics/current.hpp"
#include "unav_physics/seabed.hpp"

namespace unav::physics {

namespace {
constexpr double kTwoPi = 6.283185307179586;

bool finite3(const Eigen::Vector3d& v) { return v.allFinite(); }
}  // namespace

bool EnvironmentParams::IsValid(std::string* msg) const {
  auto fail = [&](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (!(std::isfinite(gravity) && gravity > 0.0)) return fail("gravity must be > 0 m/s^2");
  if (!(std::isfinite(water_density) && water_density > 0.0)) return fail("water_density must be > 0 kg/m^3");
  if (!(std::isfinite(atmospheric_pressure) && atmospheric_pressure >= 0.0))
    return fail("atmospheric_pressure must be >= 0 Pa");
  if (!finite3(magnetic_field_W)) return fail("magnetic_field_W must be finite");
  if (!(std::isfinite(origin_latitude_deg) && std::abs(origin_latitude_deg) < 90.0))
    return fail("origin_latitude_deg must be in (-90, 90)");
  if (!(std::isfinite(origin_longitude_deg) && std::isfinite(origin_altitude_m)))
    return fail("origin_longitude_deg and origin_altitude_m must be finite");
  return true;
}

// --- currents ---------------------------------------------------------------------------------

SinusoidalCurrent::SinusoidalCurrent(const Eigen::Vector3d& mean_W, const Eigen::Vector3d& amplitude_W,
                                     double frequency_hz, double phase_rad)
    : mean_W_(mean_W), amplitude_W_(amplitude_W), omega_(kTwoPi * frequency_hz), phase_(phase_rad) {
  if (!(finite3(mean_W) && finite3(amplitude_W) && std::isfinite(phase_rad) && std::isfinite(frequency_hz) &&
        frequency_hz > 0.0)) {
    throw ConfigError("sinusoidal current: values must be finite and frequency > 0");
  }
}
Eigen::Vector3d SinusoidalCurrent::velocity_W(double t) const {
  return mean_W_ + amplitude_W_ * std::sin(omega_ * t + phase_);
}
Eigen::Vector3d SinusoidalCurrent::acceleration_W(double t) const {
  return amplitude_W_ * (omega_ * std::cos(omega_ * t + phase_));
}

SumOfSinesCurrent::SumOfSinesCurrent(const Eigen::Vector3d& mean_W, std::vector<Component> components)
    : mean_W_(mean_W), components_(std::move(components)) {
  if (!finite3(mean_W)) throw ConfigError("sum_of_sines current: mean must be finite");
  for (const auto& c : components_) {
    if (!(finite3(c.amplitude_W) && std::isfinite(c.phase_rad) && std::isfinite(c.frequency_hz) &&
          c.frequency_hz > 0.0)) {
      throw ConfigError("sum_of_sines current: component values must be finite and frequency > 0");
    }
  }
}
Eigen::Vector3d SumOfSinesCurrent::velocity_W(double t) const {
  Eigen::Vector3d v = mean_W_;
  for (const auto& c : components_) v += c.amplitude_W * std::sin(kTwoPi * c.frequency_hz * t + c.phase_rad);
  return v;
}
Eigen::Vector3d SumOfSinesCurrent::acceleration_W(double t) const {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  for (const auto& c : components_) {
    const double w = kTwoPi * c.frequency_hz;
    a += c.amplitude_W * (w * std::cos(w * t + c.phase_rad));
  }
  return a;
}

GaussMarkovCurrent::GaussMarkovCurrent(const Eigen::Vector3d& mean_W, const Eigen::Vector3d& stddev_W,
                                       double time_constant_s, std::uint64_t seed, const Eigen::Vector3d& initial_W)
    : mean_W_(mean_W), stddev_W_(stddev_W), v_W_(initial_W), time_constant_s_(time_constant_s), rng_(seed) {
  if (!(finite3(mean_W) && finite3(stddev_W) && finite3(initial_W) && (stddev_W.array() >= 0.0).all() &&
        std::isfinite(time_constant_s) && time_constant_s > 0.0)) {
    throw ConfigError("gauss_markov current: values must be finite, stddev >= 0 and time_constant > 0");
  }
}
void GaussMarkovCurrent::step(double /*t*/, double dt) {
  const double e = std::exp(-dt / time_constant_s_);
  const double s = std::sqrt(std::max(0.0, 1.0 - e * e));
  for (int i = 0; i < 3; ++i) v_W_(i) = mean_W_(i) + e * (v_W_(i) - mean_W_(i)) + stddev_W_(i) * s * normal_(rng_);
}

// --- seabed -----------------------------------------------------------------------------------

FlatSeabed::FlatSeabed(double depth_m) : depth_m_(depth_m) {
  if (!std::isfinite(depth_m)) throw ConfigError("flat seabed: depth must be finite");
}

GridSeabed::GridSeabed(double origin_N, double origin_E, double resolution_m, std::vector<std::vector<double>> depths_m)
    : origin_N_(origin_N), origin_E_(origin_E), resolution_m_(resolution_m) {
  if (!(std::isfinite(origin_N) && std::isfinite(origin_E))) throw ConfigError("grid seabed: origin must be finite");
  if (!(std::isfinite(resolution_m) && resolution_m > 0.0)) {
    std::ostringstream os;
    os << "grid seabed: resolution must be > 0 (got " << resolution_m << ")";
    throw ConfigError(os.str());
  }
  rows_ = static_cast<int>(depths_m.size());
  cols_ = rows_ > 0 ? static_cast<int>(depths_m[0].size()) : 0;
  if (rows_ < 1 || cols_ < 1) throw ConfigError("grid seabed: depths must have at least 1 row and 1 column");
  depths_m_.reserve(static_cast<std::size_t>(rows_) * static_cast<std::size_t>(cols_));
  for (int i = 0; i < rows_; ++i) {
    const auto& row = depths_m[static_cast<std::size_t>(i)];
    if (static_cast<int>(row.size()) != cols_) {
      throw ConfigError("grid seabed: depths[" + std::to_string(i) + "] has " + std::to_string(row.size()) +
                        " values, expected " + std::to_string(cols_) + " (rows must have equal length)");
    }
    for (double d : row) {
      if (!std::isfinite(d)) throw ConfigError("grid seabed: depths[" + std::to_string(i) + "] has a non-finite value");
      depths_m_.push_back(d);
    }
  }
  shallowest_m_ = *std::min_element(depths_m_.begin(), depths_m_.end());
}

double GridSeabed::depth_at(double x_N, double y_E) const {
  const double fi = std::clamp((x_N - origin_N_) / resolution_m_, 0.0, static_cast<double>(rows_ - 1));
  const double fj = std::clamp((y_E - origin_E_) / resolution_m_, 0.0, static_cast<double>(cols_ - 1));
  const int i0 = std::min(static_cast<int>(fi), std::max(rows_ - 2, 0));
  const int j0 = std::min(static_cast<int>(fj), std::max(cols_ - 2, 0));
  const int i1 = std::min(i0 + 1, rows_ - 1), j1 = std::min(j0 + 1, cols_ - 1);
  const double a = fi - i0, b = fj - j0;
  auto d = [&](int i, int j) {
    return depths_m_[static_cast<std::size_t>(i) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(j)];
  };
  return (1 - a) * ((1 - b) * d(i0, j0) + b * d(i0, j1)) + a * ((1 - b) * d(i1, j0) + b * d(i1, j1));
}

}  // namespace unav::physics

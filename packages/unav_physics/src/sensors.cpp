// Sensor models.
#include "unav_physics/sensors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "unav_physics/seabed.hpp"

namespace unav::physics {

namespace {
constexpr double kEarthRadius = 6378137.0;  // m, WGS-84 equatorial (flat-earth GPS conversion)
constexpr double kDegPerRad = 57.29577951308232;

double period_of(bool enabled, double rate_hz) { return enabled && rate_hz > 0.0 ? 1.0 / rate_hz : 0.0; }
}  // namespace

SensorSuite::SensorSuite(const SensorSuiteParams& params, const EnvironmentParams& env) : params_(params), env_(env) {
  // Independent streams: enabling one sensor does not change another's noise.
  const std::uint64_t s = static_cast<std::uint64_t>(params.seed) * 0x9E3779B97F4A7C15ULL;
  g_imu_.gen.seed(s + 1);
  g_pressure_.gen.seed(s + 2);
  g_dvl_.gen.seed(s + 3);
  g_alt_.gen.seed(s + 4);
  g_mag_.gen.seed(s + 5);
  g_gps_.gen.seed(s + 6);
  usbl_ = Usbl(params.usbl, s + 7);
  s_imu_.period = period_of(params.imu.enabled, params.imu.rate_hz);
  s_pressure_.period = period_of(params.pressure.enabled, params.pressure.rate_hz);
  s_dvl_.period = period_of(params.dvl.enabled, params.dvl.rate_hz);
  s_alt_.period = period_of(params.altimeter.enabled, params.altimeter.rate_hz);
  s_mag_.period = period_of(params.magnetometer.enabled, params.magnetometer.rate_hz);
  s_gps_.period = period_of(params.gps.enabled, params.gps.rate_hz);
  auto init = [](Channel& c, const NoiseParams& p) {
    c.p = p;
    c.bias = p.initial_bias;
  };
  for (int i = 0; i < 3; ++i) {
    init(accel_[i], params.imu.accel);
    init(gyro_[i], params.imu.gyro);
    init(mag_[i], params.magnetometer.field);
    init(gps_[i], i < 2 ? params.gps.horizontal : params.gps.vertical);
  }
  for (auto& c : dvl_) init(c, params.dvl.velocity);
  init(pressure_, params.pressure.pressure);
  init(range_, params.altimeter.range);
}

Eigen::Vector3d dvl_beam_B(int i, double beam_angle_deg) {
  const double a = beam_angle_deg / kDegPerRad, az = (45.0 + 90.0 * i) / kDegPerRad;
  return {std::sin(a) * std::cos(az), std::sin(a) * std::sin(az), std::cos(a)};
}

double seabed_ray_range(const Seabed& seabed, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                        double max_range) {
  // Below the seabed (depth > seabed depth) along the ray: g(s) = z(s) - depth(x(s), y(s)) > 0.
  auto g = [&](double s) {
    const Eigen::Vector3d p = origin + s * dir;
    return p.z() - seabed.depth_at(p.x(), p.y());
  };
  if (g(0.0) >= 0.0) return -1.0;  // the sensor is in (or under) the seabed
  constexpr double kStep = 0.05;   // m: the seabed's relief varies over metres (grids of 1 m cells)
  // Above the seabed's shallowest depth the ray cannot reach it: the march starts a step before
  // the ray gets there (a DVL 20 m up marches ~10 steps instead of ~400).
  double lo = 0.0;
  const double top = seabed.shallowest_depth();
  if (origin.z() < top) {
    if (dir.z() <= 0.0) return -1.0;  // level or rising: never
    lo = std::max(0.0, std::floor((top - origin.z()) / dir.z() / kStep) - 1.0) * kStep;
  }
  for (double hi = lo + kStep; lo < max_range; lo = hi, hi += kStep) {
    hi = std::min(hi, max_range);
    if (g(hi) >= 0.0) {
      for (int k = 0; k < 60 && hi - lo > 1e-12; ++k) {
        const double mid = 0.5 * (lo + hi);
        (g(mid) >= 0.0 ? hi : lo) = mid;
      }
      // A last secant step: exact (to rounding) where the bottom is locally a plane.
      const double g_lo = g(lo), g_hi = g(hi);
      return g_hi > g_lo ? lo - g_lo * (hi - lo) / (g_hi - g_lo) : hi;
    }
  }
  return -1.0;
}

double SensorSuite::noisy(Channel& c, Gaussian& g, double truth, double dt) {
  if (c.p.bias_random_walk > 0.0) c.bias += c.p.bias_random_walk * std::sqrt(dt) * g();
  const double n = c.p.noise_stddev > 0.0 ? c.p.noise_stddev * g() : 0.0;
  return truth + c.bias + n;
}

void SensorSuite::update(double t, const RigidBodyState& x, const Vector6d& nu_dot, const Seabed* seabed) {
  const Eigen::Matrix3d R = x.q_WB.normalized().toRotationMatrix();
  const double z = x.p_WB_W.z();
  const bool underwater = z > 0.0;

  if (s_imu_.due(t)) {
    auto& r = readings_.imu;
    // Specific force: inertial acceleration of the body origin minus gravity, in body axes.
    const Eigen::Vector3d a_B = nu_dot.head<3>() + x.w_WB_B.cross(x.v_WB_B);
    const Eigen::Vector3d f_B = a_B - R.transpose() * Eigen::Vector3d(0.0, 0.0, env_.gravity);
    for (int i = 0; i < 3; ++i) {
      r.specific_force_B(i) = noisy(accel_[i], g_imu_, f_B(i), s_imu_.period);
      r.angular_rate_B(i) = noisy(gyro_[i], g_imu_, x.w_WB_B(i), s_imu_.period);
    }
    r.q_WB = x.q_WB;
    r.valid = true;
    r.stamp = t;
    ++r.seq;
    s_imu_.advance(t);
  }
  if (s_pressure_.due(t)) {
    auto& r = readings_.pressure;
    const double rho_g = env_.water_density * env_.gravity;
    r.pressure_pa =
        noisy(pressure_, g_pressure_, env_.atmospheric_pressure + rho_g * std::max(z, 0.0), s_pressure_.period);
    r.depth_m = (r.pressure_pa - env_.atmospheric_pressure) / rho_g;
    r.valid = true;
    r.stamp = t;
    ++r.seq;
    s_pressure_.advance(t);
  }
  const double altitude = seabed != nullptr ? seabed->depth_at(x.p_WB_W.x(), x.p_WB_W.y()) - z : 0.0;
  if (s_dvl_.due(t)) {
    auto& r = readings_.dvl;
    const auto& p = params_.dvl;
    if (p.beams == 0) {
      r.valid = seabed != nullptr && underwater && altitude >= p.min_altitude && altitude <= p.max_altitude;
      if (r.valid) {
        for (int i = 0; i < 3; ++i) r.velocity_B(i) = noisy(dvl_[i], g_dvl_, x.v_WB_B(i), s_dvl_.period);
        r.altitude_m = altitude;
      }
    } else {
      update_dvl_beams(x, R, seabed, underwater);
    }
    r.stamp = t;
    ++r.seq;
    s_dvl_.advance(t);
  }
  if (s_alt_.due(t)) {
    auto& r = readings_.altimeter;
    const auto& p = params_.altimeter;
    const double cos_tilt = R(2, 2);  // body +z projected on NED down
    r.valid = false;
    if (seabed != nullptr && underwater && cos_tilt > 0.1 && altitude > 0.0) {
      const double range = altitude / cos_tilt;  // locally flat seabed
      r.valid = range >= p.min_range && range <= p.max_range;
      if (r.valid) r.range_m = noisy(range_, g_alt_, range, s_alt_.period);
    }
    r.stamp = t;
    ++r.seq;
    s_alt_.advance(t);
  }
  if (s_mag_.due(t)) {
    auto& r = readings_.magnetometer;
    const Eigen::Vector3d m_B = R.transpose() * env_.magnetic_field_W;
    for (int i = 0; i < 3; ++i) r.field_B(i) = noisy(mag_[i], g_mag_, m_B(i), s_mag_.period);
    r.valid = true;
    r.stamp = t;
    ++r.seq;
    s_mag_.advance(t);
  }
  if (s_gps_.due(t)) {
    auto& r = readings_.gps;
    r.valid = z <= params_.gps.max_depth;
    if (r.valid) {
      for (int i = 0; i < 3; ++i) r.p_W(i) = noisy(gps_[i], g_gps_, x.p_WB_W(i), s_gps_.period);
      const double lat0 = env_.origin_latitude_deg / kDegPerRad;
      r.latitude_deg = env_.origin_latitude_deg + r.p_W.x() / kEarthRadius * kDegPerRad;
      r.longitude_deg = env_.origin_longitude_deg + r.p_W.y() / (kEarthRadius * std::cos(lat0)) * kDegPerRad;
      r.altitude_m = env_.origin_altitude_m - r.p_W.z();
    }
    r.stamp = t;
    ++r.seq;
    s_gps_.advance(t);
  }
  if (params_.usbl.enabled && usbl_.step(t, x.p_WB_W + R * params_.usbl.transponder_xyz_m))
    readings_.usbl = usbl_.reading();
}

namespace {
[[noreturn]] void sensor_fail(const std::string& source, const std::string& key, double value,
                              const std::string& rule) {
  std::ostringstream os;
  os << value;
  throw ConfigError(source, "sensors." + key, os.str(), rule);
}
void check_rate(const std::string& src, const std::string& key, bool enabled, double rate) {
  if (enabled && !(std::isfinite(rate) && rate > 0.0)) sensor_fail(src, key + ".rate", rate, "must be > 0 Hz");
}
void check_noise(const std::string& src, const std::string& key, const NoiseParams& n) {
  if (!(std::isfinite(n.noise_stddev) && n.noise_stddev >= 0.0))
    sensor_fail(src, key + ".noise_stddev", n.noise_stddev, "must be >= 0");
  if (!(std::isfinite(n.bias_random_walk) && n.bias_random_walk >= 0.0))
    sensor_fail(src, key + ".bias_random_walk", n.bias_random_walk, "must be >= 0");
  if (!std::isfinite(n.initial_bias)) sensor_fail(src, key + ".initial_bias", n.initial_bias, "must be finite");
}
void check_range(const std::string& src, const std::string& lo_key, const std::string& hi_key, double lo, double hi) {
  if (!(std::isfinite(lo) && lo >= 0.0)) sensor_fail(src, lo_key, lo, "must be >= 0 m");
  if (!(std::isfinite(hi) && hi > lo)) sensor_fail(src, hi_key, hi, "must be finite and > sensors." + lo_key);
}
}  // namespace

// Four beams: ray casts, lock, per-beam velocity, least-squares solution (see DvlParams).
void SensorSuite::update_dvl_beams(const RigidBodyState& x, const Eigen::Matrix3d& R, const Seabed* seabed,
                                   bool underwater) {
  auto& r = readings_.dvl;
  const auto& p = params_.dvl;
  const double max_range = p.max_altitude / std::cos(p.beam_angle_deg / kDegPerRad) + 1.0;
  const double cos_max_incidence = std::cos(p.max_incidence_deg / kDegPerRad);
  Eigen::Matrix<double, 4, 3> B;
  Eigen::Vector4d m;
  int n = 0;
  double vertical_sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    r.beam_valid[static_cast<std::size_t>(i)] = false;
    const Eigen::Vector3d b_B = dvl_beam_B(i, p.beam_angle_deg), d_W = R * b_B;
    const double s = seabed != nullptr && underwater ? seabed_ray_range(*seabed, x.p_WB_W, d_W, max_range) : -1.0;
    if (s < 0.0) continue;
    const Eigen::Vector3d hit = x.p_WB_W + s * d_W;
    const double vertical = s * d_W.z();
    // The bottom's normal (up, NED: -z) from the height field's slope at the hit.
    constexpr double h = 0.05;
    const double dzdx = (seabed->depth_at(hit.x() + h, hit.y()) - seabed->depth_at(hit.x() - h, hit.y())) / (2 * h);
    const double dzdy = (seabed->depth_at(hit.x(), hit.y() + h) - seabed->depth_at(hit.x(), hit.y() - h)) / (2 * h);
    const Eigen::Vector3d up = Eigen::Vector3d(dzdx, dzdy, -1.0).normalized();
    if (vertical < p.min_altitude || vertical > p.max_altitude || -d_W.dot(up) < cos_max_incidence) continue;
    // The sensor's velocity over the (still) bottom, along the beam, with the beam's noise.
    const double v_beam = noisy(dvl_[i], g_dvl_, b_B.dot(x.v_WB_B), s_dvl_.period);
    r.beam_valid[static_cast<std::size_t>(i)] = true;
    r.beam_range_m[static_cast<std::size_t>(i)] = s;
    r.beam_velocity[static_cast<std::size_t>(i)] = v_beam;
    B.row(n) = b_B.transpose();
    m(n) = v_beam;
    vertical_sum += vertical;
    ++n;
  }
  r.locked_beams = n;
  r.valid = n >= 3;
  if (r.valid) {
    r.velocity_B = B.topRows(n).colPivHouseholderQr().solve(m.head(n));
    r.altitude_m = vertical_sum / n;
  }
}

void validate_sensors(const SensorSuiteParams& p, const std::string& src) {
  check_rate(src, "imu", p.imu.enabled, p.imu.rate_hz);
  check_noise(src, "imu.accel", p.imu.accel);
  check_noise(src, "imu.gyro", p.imu.gyro);
  check_rate(src, "pressure", p.pressure.enabled, p.pressure.rate_hz);
  check_noise(src, "pressure", p.pressure.pressure);
  check_rate(src, "dvl", p.dvl.enabled, p.dvl.rate_hz);
  check_noise(src, "dvl", p.dvl.velocity);
  check_range(src, "dvl.min_altitude", "dvl.max_altitude", p.dvl.min_altitude, p.dvl.max_altitude);
  if (p.dvl.beams != 0 && p.dvl.beams != 4)
    sensor_fail(src, "dvl.beams", p.dvl.beams, "must be 4 (a Janus array) or 0 (the ideal sensor)");
  if (!(p.dvl.beam_angle_deg > 0.0 && p.dvl.beam_angle_deg < 60.0))
    sensor_fail(src, "dvl.beam_angle_deg", p.dvl.beam_angle_deg, "must be in (0, 60) deg off the down axis");
  if (!(p.dvl.max_incidence_deg > 0.0 && p.dvl.max_incidence_deg < 90.0))
    sensor_fail(src, "dvl.max_incidence_deg", p.dvl.max_incidence_deg, "must be in (0, 90) deg");
  check_rate(src, "altimeter", p.altimeter.enabled, p.altimeter.rate_hz);
  check_noise(src, "altimeter", p.altimeter.range);
  check_range(src, "altimeter.min_range", "altimeter.max_range", p.altimeter.min_range, p.altimeter.max_range);
  check_rate(src, "magnetometer", p.magnetometer.enabled, p.magnetometer.rate_hz);
  check_noise(src, "magnetometer", p.magnetometer.field);
  check_rate(src, "gps", p.gps.enabled, p.gps.rate_hz);
  check_noise(src, "gps.horizontal", p.gps.horizontal);
  check_noise(src, "gps.vertical", p.gps.vertical);
  if (!(std::isfinite(p.gps.max_depth) && p.gps.max_depth >= 0.0))
    sensor_fail(src, "gps.max_depth", p.gps.max_depth, "must be >= 0 m");
}

}  // namespace unav::physics

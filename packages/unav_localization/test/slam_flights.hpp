// The flights (body poses in the pipe-inspection world, frame k at t = 0.1 k) whose rendered
// images the SLAM and VO tests run on: render_slam_sequences draws them (slam_sequences.hpp), the
// tests that also need the motion itself (the IMU of the weave) read it here. No renderer.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

namespace unav::localization::testing {

inline Eigen::Matrix3d Rot(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// 100 frames: 6 m north at 6 cm per frame 1.5 m above the pipe, swaying 0.3 m east and
// yawing +-0.1 rad, as the pipe-following controller flies it.
inline std::vector<Eigen::Isometry3d> StraightPath() {
  std::vector<Eigen::Isometry3d> X_WB;
  for (int k = 0; k < 100; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(-1.0 + 0.06 * k, 0.3 * std::sin(0.05 * k), 8.35);
    X.linear() = Rot(0, 0, 0.1 * std::sin(0.04 * k));
    X_WB.push_back(X);
  }
  return X_WB;
}

// 60 frames north at `step_m` per frame, swaying 0.2 m and yawing +-0.05 rad (the forward-looking
// camera's flights).
inline std::vector<Eigen::Isometry3d> ForwardPath(double step_m) {
  std::vector<Eigen::Isometry3d> X_WB;
  for (int k = 0; k < 60; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(-4.0 + step_m * k, 0.6 + 0.2 * std::sin(0.05 * k), 8.5);
    X.linear() = Rot(0, 0, 0.05 * std::sin(0.07 * k));
    X_WB.push_back(X);
  }
  return X_WB;
}

// The forward-looking camera's three flights: pitched down 15, 25, 35 deg at 0.6, 1.0, 1.5 m/s
// (sequences forward_15, forward_25, forward_35).
struct ForwardCase {
  int pitch_deg;
  double step_m;
};
inline constexpr ForwardCase kForwardCases[] = {{15, 0.06}, {25, 0.10}, {35, 0.15}};

// Optical frame (x right, y down, z ahead) in the body (x ahead, y right, z down), pitched down.
inline Eigen::Isometry3d ForwardMount(double pitch_deg) {
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d ahead;
  ahead << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  X_BC.linear() = Rot(0, -pitch_deg * M_PI / 180.0, 0) * ahead;
  return X_BC;
}

// 3.6 m x 3.6 m square at constant heading (north, east, south, west) and 1.2 m on past the
// start, 6 cm per frame: the camera sees its first images again after 14.4 m.
inline std::vector<Eigen::Isometry3d> SquarePath() {
  std::vector<Eigen::Isometry3d> X_WB;
  const std::vector<Eigen::Vector2d> dirs{{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  Eigen::Vector2d p(2.0, -1.8);
  for (std::size_t leg = 0; leg < dirs.size(); ++leg) {
    const int steps = leg + 1 < dirs.size() ? 60 : 20;
    for (int k = 0; k < steps; ++k) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.translation() = Eigen::Vector3d(p.x(), p.y(), 8.35);
      X_WB.push_back(X);
      p += 0.06 * dirs[leg];
    }
  }
  return X_WB;
}

// A weaving flight, continuous in time: 0.5 m/s north, swaying 0.3 m and heaving 0.15 m with
// ~0.3 m/s^2 of acceleration (what an inertial initialisation needs to see scale), yawing
// +-0.15 rad; its ideal IMU in closed form. Its 10 s (100 frames) are rendered.
struct WeaveFlight {
  static Eigen::Vector3d P(double t) { return {-1.0 + 0.5 * t, 0.3 * std::sin(t), 8.35 + 0.15 * std::sin(1.3 * t)}; }
  static Eigen::Vector3d A(double t) { return {0.0, -0.3 * std::sin(t), -0.15 * 1.69 * std::sin(1.3 * t)}; }
  static double Yaw(double t) { return 0.15 * std::sin(0.6 * t); }
  static Eigen::Vector3d V(double t) { return {0.5, 0.3 * std::cos(t), 0.15 * 1.3 * std::cos(1.3 * t)}; }
  static double YawRate(double t) { return 0.09 * std::cos(0.6 * t); }
  static Eigen::Isometry3d X_WB(double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = P(t);
    X.linear() = Rot(0, 0, Yaw(t));
    return X;
  }
  static std::vector<Eigen::Isometry3d> Path() {
    std::vector<Eigen::Isometry3d> X;
    X.reserve(100);
    for (int k = 0; k < 100; ++k) X.push_back(X_WB(0.1 * k));
    return X;
  }
};

// The KLT VO tests' flight, 2 m above the sand: 5 cm north per frame, yawing 0.005 rad and
// sinking 5 mm per frame, 70 frames.
inline std::vector<Eigen::Isometry3d> KltPath() {
  std::vector<Eigen::Isometry3d> X_WB;
  for (int k = 0; k < 70; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(-2.0 + 0.05 * k, 1.5, 7.8 + 0.005 * k);
    X.linear() = Eigen::AngleAxisd(0.005 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X_WB.push_back(X);
  }
  return X_WB;
}

// The node tests' flights over the pipe, 1.5 m up: `frames` frames `step_m` apart northwards,
// swaying sway_m sin(0.1 k) and yawing yaw_rad sin(0.08 k). orb_slam: 50, 0.06, 0.2, 0.05;
// klt_vo: 40, 0.05, 0.15, 0.
inline std::vector<Eigen::Isometry3d> NodePath(int frames, double step_m, double sway_m, double yaw_rad) {
  std::vector<Eigen::Isometry3d> X_WB;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(-1.0 + step_m * k, sway_m * std::sin(0.1 * k), 8.35);
    X.linear() = Eigen::AngleAxisd(yaw_rad * std::sin(0.08 * k), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X_WB.push_back(X);
  }
  return X_WB;
}

}  // namespace unav::localization::testing

#include "unav_evaluation/trajectory.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace unav::evaluation {

double Trajectory::path_length() const {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) length += (poses[i].translation() - poses[i - 1].translation()).norm();
  return length;
}

Trajectory read_tum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw TrajectoryError(path + ": cannot be opened (missing or unreadable)");
  Trajectory traj;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    for (char& c : line)
      if (c == ',') c = ' ';  // evo also accepts comma-separated TUM files
    std::istringstream ss(line);
    std::vector<double> v;
    std::string tok;
    while (ss >> tok) {
      char* end = nullptr;
      const double x = std::strtod(tok.c_str(), &end);
      if (*end != '\0') throw TrajectoryError(path + ":" + std::to_string(line_no) + ": '" + tok + "' is not a number");
      if (!std::isfinite(x))
        throw TrajectoryError(path + ":" + std::to_string(line_no) + ": value '" + tok + "' is not finite");
      v.push_back(x);
    }
    if (v.size() != 8)
      throw TrajectoryError(path + ":" + std::to_string(line_no) +
                            ": expected 8 columns (timestamp tx ty tz qx qy qz qw), got " + std::to_string(v.size()));
    if (!traj.empty() && v[0] <= traj.stamps.back())
      throw TrajectoryError(path + ":" + std::to_string(line_no) + ": timestamp " + tok +
                            " is not after the previous one (" + std::to_string(traj.stamps.back()) +
                            "): times must increase");
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-3)
      throw TrajectoryError(path + ":" + std::to_string(line_no) + ": quaternion norm " + std::to_string(q.norm()) +
                            " is not 1 (within 1e-3)");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    traj.push_back(v[0], T);
  }
  if (traj.empty()) throw TrajectoryError(path + ": contains no poses");
  return traj;
}

void write_tum(const std::string& path, const Trajectory& traj) {
  std::ofstream out(path);
  if (!out) throw TrajectoryError(path + ": cannot be written");
  out << std::setprecision(9) << std::fixed;
  for (size_t i = 0; i < traj.size(); ++i) {
    const Eigen::Vector3d p = traj.poses[i].translation();
    const Eigen::Quaterniond q(traj.poses[i].linear());
    out << traj.stamps[i] << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' '
        << q.z() << ' ' << q.w() << '\n';
  }
  out.flush();
  if (!out) throw TrajectoryError(path + ": write failed");
}

std::pair<Trajectory, Trajectory> associate(const Trajectory& first, const Trajectory& second, double max_diff_s,
                                            double offset_s) {
  // evo: the shorter trajectory's stamps look up the nearest stamp of the longer one.
  const bool second_longer = second.size() > first.size();
  const Trajectory& shorter = second_longer ? first : second;
  const Trajectory& longer = second_longer ? second : first;
  const double offset_long = second_longer ? offset_s : -offset_s;
  Trajectory out_short, out_long;
  for (size_t i = 0; i < shorter.size(); ++i) {
    const double t = shorter.stamps[i];
    // Longer stamps are increasing: binary search for the nearest after the offset.
    size_t lo = 0, hi = longer.size();
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (longer.stamps[mid] + offset_long < t)
        lo = mid + 1;
      else
        hi = mid;
    }
    size_t best = lo < longer.size() ? lo : longer.size() - 1;
    if (lo > 0 && std::abs(longer.stamps[lo - 1] + offset_long - t) <= std::abs(longer.stamps[best] + offset_long - t))
      best = lo - 1;
    if (std::abs(longer.stamps[best] + offset_long - t) <= max_diff_s) {
      out_short.push_back(shorter.stamps[i], shorter.poses[i]);
      out_long.push_back(longer.stamps[best], longer.poses[best]);
    }
  }
  if (out_short.empty()) {
    std::ostringstream os;
    os << "no pose pairs within max_diff " << max_diff_s
       << " s: the trajectories do not overlap in time (first: " << (first.empty() ? 0.0 : first.stamps.front()) << ".."
       << (first.empty() ? 0.0 : first.stamps.back())
       << " s, second: " << (second.empty() ? 0.0 : second.stamps.front()) << ".."
       << (second.empty() ? 0.0 : second.stamps.back()) << " s)";
    throw TrajectoryError(os.str());
  }
  if (second_longer) return {out_short, out_long};
  return {out_long, out_short};
}

}  // namespace unav::evaluation

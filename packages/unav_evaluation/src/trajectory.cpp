#include "unav_evaluation/trajectory.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

namespace unav::evaluation {

double Trajectory::path_length() const {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) length += (poses[i].translation() - poses[i - 1].translation()).norm();
  return length;
}

namespace {

// Numbers of one line of a text trajectory file, split at blanks and commas. Errors name the
// file, line and column (1-based, with its name when `names` has one).
std::vector<double> parse_numbers(const std::string& path, int line_no, std::string line,
                                  const std::vector<std::string>& names) {
  for (char& c : line)
    if (c == ',') c = ' ';
  std::istringstream ss(line);
  std::vector<double> v;
  std::string tok;
  while (ss >> tok) {
    const size_t col = v.size() + 1;
    const std::string where = path + ":" + std::to_string(line_no) + ": column " + std::to_string(col) +
                              (col <= names.size() ? " (" + names[col - 1] + ")" : "");
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (*end != '\0') throw TrajectoryError(where + ": '" + tok + "' is not a number");
    if (!std::isfinite(x)) throw TrajectoryError(where + ": value '" + tok + "' is not finite");
    v.push_back(x);
  }
  return v;
}

bool skip_line(const std::string& line) {
  const size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

std::string fmt(double x) {
  std::ostringstream o;
  o << std::setprecision(17) << x;
  return o.str();
}

Eigen::Isometry3d pose_from(const std::string& where, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  if (std::abs(q.norm() - 1.0) > 1e-3)
    throw TrajectoryError(where + ": quaternion norm " + std::to_string(q.norm()) + " is not 1 (within 1e-3)");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = p;
  return T;
}

void check_order(const std::string& where, const Trajectory& traj, double stamp) {
  if (!traj.empty() && stamp < traj.stamps.back())
    throw TrajectoryError(where + ": column 1 (timestamp): " + fmt(stamp) + " is before the previous stamp " +
                          fmt(traj.stamps.back()) + ": timestamps must not decrease");
}

// Reads a text trajectory file: each data line ('#' comments and blanks skipped) is split into
// numbers (errors name file, line and column) and handed to `add` with "file:line" for its own
// errors. Throws when the file cannot be opened or holds no pose.
Trajectory read_lines(const std::string& path, const std::vector<std::string>& names,
                      const std::function<void(const std::string&, const std::vector<double>&, Trajectory&)>& add) {
  std::ifstream in(path);
  if (!in) throw TrajectoryError(path + ": cannot be opened (missing or unreadable)");
  Trajectory traj;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (skip_line(line)) continue;
    add(path + ":" + std::to_string(line_no), parse_numbers(path, line_no, line, names), traj);
  }
  if (traj.empty()) throw TrajectoryError(path + ": contains no poses");
  return traj;
}

}  // namespace

Trajectory read_tum(const std::string& path) {
  static const std::vector<std::string> names = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  return read_lines(path, names, [](const std::string& where, const std::vector<double>& v, Trajectory& traj) {
    if (v.size() != 8)
      throw TrajectoryError(where + ": expected 8 columns (timestamp tx ty tz qx qy qz qw), got " +
                            std::to_string(v.size()));
    check_order(where, traj, v[0]);
    traj.push_back(v[0], pose_from(where + ": columns 5-8 (qx qy qz qw)", Eigen::Vector3d(v[1], v[2], v[3]),
                                   Eigen::Quaterniond(v[7], v[4], v[5], v[6])));
  });
}

Trajectory read_kitti(const std::string& path) {
  static const std::vector<std::string> names = {"r11", "r12", "r13", "tx",  "r21", "r22",
                                                 "r23", "ty",  "r31", "r32", "r33", "tz"};
  return read_lines(path, names, [](const std::string& where, const std::vector<double>& v, Trajectory& traj) {
    if (v.size() != 12)
      throw TrajectoryError(where + ": expected 12 columns (a row-major 3x4 pose [R | t]), got " +
                            std::to_string(v.size()));
    Eigen::Matrix3d R;
    R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double orth = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (orth > 1e-3 || std::abs(R.determinant() - 1.0) > 1e-3)
      throw TrajectoryError(where + ": columns 1-3, 5-7, 9-11 (R): not a rotation (|R^T R - I| = " +
                            std::to_string(orth) + ", det " + std::to_string(R.determinant()) + ")");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
    traj.push_back(static_cast<double>(traj.size()), T);
  });
}

Trajectory read_euroc_csv(const std::string& path) {
  static const std::vector<std::string> names = {"timestamp [ns]", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z"};
  return read_lines(path, names, [](const std::string& where, const std::vector<double>& v, Trajectory& traj) {
    if (v.size() < 8)
      throw TrajectoryError(where +
                            ": expected at least 8 columns (timestamp[ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z), got " +
                            std::to_string(v.size()));
    const double stamp = v[0] * 1e-9;
    check_order(where, traj, stamp);
    traj.push_back(stamp, pose_from(where + ": columns 5-8 (q_w q_x q_y q_z)", Eigen::Vector3d(v[1], v[2], v[3]),
                                    Eigen::Quaterniond(v[4], v[5], v[6], v[7])));
  });
}

TrajectoryFormat trajectory_format_from_string(const std::string& name) {
  if (name == "tum") return TrajectoryFormat::kTum;
  if (name == "kitti") return TrajectoryFormat::kKitti;
  if (name == "euroc") return TrajectoryFormat::kEuroc;
  throw TrajectoryError("trajectory format '" + name + "' is unknown (tum, kitti, euroc)");
}

Trajectory read_trajectory(const std::string& path, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kKitti:
      return read_kitti(path);
    case TrajectoryFormat::kEuroc:
      return read_euroc_csv(path);
    case TrajectoryFormat::kTum:
      break;
  }
  return read_tum(path);
}

void write_kitti(const std::string& path, const Trajectory& traj) {
  std::ofstream out(path);
  if (!out) throw TrajectoryError(path + ": cannot be written");
  out << std::setprecision(9) << std::scientific;
  for (const auto& T : traj.poses) {
    const Eigen::Matrix3d R = T.linear();
    const Eigen::Vector3d t = T.translation();
    for (int r = 0; r < 3; ++r)
      out << R(r, 0) << ' ' << R(r, 1) << ' ' << R(r, 2) << ' ' << t(r) << (r < 2 ? ' ' : '\n');
  }
  out.flush();
  if (!out) throw TrajectoryError(path + ": write failed");
}

std::pair<Trajectory, Trajectory> pair_by_index(const Trajectory& first, const Trajectory& second) {
  if (first.size() != second.size())
    throw TrajectoryError("trajectories must have same number of poses (" + std::to_string(first.size()) + " and " +
                          std::to_string(second.size()) + "): KITTI files are compared pose by pose");
  return {first, second};
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
    // numpy's argmin: the first of equal stamps.
    while (best > 0 && longer.stamps[best - 1] == longer.stamps[best]) --best;
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

namespace unav::evaluation {

namespace {
constexpr size_t kSpoolRecord = 13;  // doubles: stamp, then R row-major with t as the 4th column
}  // namespace

void TrajectorySpool::push_back(double stamp, const Eigen::Isometry3d& pose) {
  if (!out_.is_open()) {
    out_.open(path_, std::ios::binary | std::ios::trunc);
    if (!out_) throw TrajectoryError(path_ + ": cannot create the trajectory spool");
  }
  double r[kSpoolRecord];
  r[0] = stamp;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) r[1 + 4 * i + j] = pose.matrix()(i, j);
  out_.write(reinterpret_cast<const char*>(r), sizeof(r));
  if (!out_) throw TrajectoryError(path_ + ": cannot write the trajectory spool");
  ++size_;
  last_stamp_ = stamp;
}

Trajectory TrajectorySpool::load() {
  Trajectory t;
  if (size_ == 0) return t;
  out_.flush();
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw TrajectoryError(path_ + ": cannot read the trajectory spool");
  t.stamps.reserve(size_);
  t.poses.reserve(size_);
  double r[kSpoolRecord];
  for (size_t k = 0; k < size_; ++k) {
    if (!in.read(reinterpret_cast<char*>(r), sizeof(r)))
      throw TrajectoryError(path_ + ": the trajectory spool ends at pose " + std::to_string(k) + " of " +
                            std::to_string(size_));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) X.matrix()(i, j) = r[1 + 4 * i + j];
    t.push_back(r[0], X);
  }
  return t;
}

void TrajectorySpool::remove() {
  if (out_.is_open()) out_.close();
  std::remove(path_.c_str());
  size_ = 0;
  last_stamp_ = 0.0;
}

void PathHistory::update(const Trajectory& path) {
  for (size_t i = 0; i < path.size(); ++i) poses_[std::llround(path.stamps[i] * 1e9)] = {path.stamps[i], path.poses[i]};
}

Trajectory PathHistory::over(const Trajectory& odometry) const {
  if (poses_.empty()) return odometry;
  const double first = poses_.begin()->second.first, last = poses_.rbegin()->second.first;
  Trajectory t;
  for (size_t i = 0; i < odometry.size() && odometry.stamps[i] < first; ++i)
    t.push_back(odometry.stamps[i], odometry.poses[i]);
  for (const auto& [ns, p] : poses_) t.push_back(p.first, p.second);
  for (size_t i = 0; i < odometry.size(); ++i)
    if (odometry.stamps[i] > last) t.push_back(odometry.stamps[i], odometry.poses[i]);
  return t;
}

}  // namespace unav::evaluation

#include "unav_localization/image_sequence.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace unav::localization {
namespace fs = std::filesystem;

namespace {

double Number(const YAML::Node& n, const std::string& file, const std::string& key) {
  if (!n) throw InputError(file + ": key '" + key + "' is missing");
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(file + ": key '" + key + "' must be a number, got '" + n.as<std::string>("?") + "'");
  }
  if (!std::isfinite(v)) throw InputError(file + ": key '" + key + "' must be finite, got " + n.as<std::string>("?"));
  return v;
}

}  // namespace

CameraFile LoadCameraFile(const std::string& path) {
  YAML::Node y;
  try {
    y = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path + ": cannot be read");
  } catch (const YAML::Exception& e) {
    throw InputError(path + ": not valid YAML: " + e.what());
  }
  if (!y.IsMap()) throw InputError(path + ": expected a map of camera keys");
  CameraFile c;
  auto& k = c.camera;
  if (y["intrinsics"] && y["resolution"]) {  // EuRoC's cam0/sensor.yaml
    const YAML::Node in = y["intrinsics"], res = y["resolution"];
    if (!in.IsSequence() || in.size() != 4) throw InputError(path + ": key 'intrinsics' must hold fu, fv, cu, cv");
    if (!res.IsSequence() || res.size() != 2) throw InputError(path + ": key 'resolution' must hold width, height");
    k.width = static_cast<int>(Number(res[0], path, "resolution[0]"));
    k.height = static_cast<int>(Number(res[1], path, "resolution[1]"));
    k.fx = Number(in[0], path, "intrinsics[0]");
    k.fy = Number(in[1], path, "intrinsics[1]");
    k.cx = Number(in[2], path, "intrinsics[2]");
    k.cy = Number(in[3], path, "intrinsics[3]");
    if (const YAML::Node dist = y["distortion_coefficients"])  // radial-tangential k1 k2 p1 p2
      for (size_t i = 0; i < dist.size(); ++i) c.distortion.push_back(Number(dist[i], path, "distortion_coefficients"));
  } else if (y["camera_matrix"]) {  // ROS camera_info YAML
    k.width = static_cast<int>(Number(y["image_width"], path, "image_width"));
    k.height = static_cast<int>(Number(y["image_height"], path, "image_height"));
    const YAML::Node d = y["camera_matrix"]["data"];
    if (!d || !d.IsSequence() || d.size() != 9)
      throw InputError(path + ": key 'camera_matrix.data' must hold 9 numbers");
    k.fx = Number(d[0], path, "camera_matrix.data[0]");
    k.cx = Number(d[2], path, "camera_matrix.data[2]");
    k.fy = Number(d[4], path, "camera_matrix.data[4]");
    k.cy = Number(d[5], path, "camera_matrix.data[5]");
    if (const YAML::Node dist = y["distortion_coefficients"]["data"])
      for (size_t i = 0; i < dist.size(); ++i)
        c.distortion.push_back(Number(dist[i], path, "distortion_coefficients.data"));
  } else {
    k.width = static_cast<int>(Number(y["width"], path, "width"));
    k.height = static_cast<int>(Number(y["height"], path, "height"));
    k.fx = Number(y["fx"], path, "fx");
    k.fy = Number(y["fy"], path, "fy");
    k.cx = Number(y["cx"], path, "cx");
    k.cy = Number(y["cy"], path, "cy");
    if (y["depth_scale"]) {
      c.depth_scale = Number(y["depth_scale"], path, "depth_scale");
      if (!(c.depth_scale > 0)) throw InputError(path + ": key 'depth_scale' must be > 0");
    }
    if (const YAML::Node dist = y["distortion"]) {
      if (!dist.IsSequence()) throw InputError(path + ": key 'distortion' must be a list of numbers");
      for (size_t i = 0; i < dist.size(); ++i) c.distortion.push_back(Number(dist[i], path, "distortion"));
    }
  }
  if (k.width <= 0 || k.height <= 0)
    throw InputError(path + ": image size must be positive, got " + std::to_string(k.width) + "x" +
                     std::to_string(k.height));
  if (!(k.fx > 0 && k.fy > 0)) throw InputError(path + ": fx and fy must be > 0");
  if (c.distortion.size() > 8)
    throw InputError(path + ": at most 8 distortion coefficients, got " + std::to_string(c.distortion.size()));
  return c;
}

std::vector<SequenceImage> ListImages(const std::string& dir, double fps) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": not a folder");
  std::vector<SequenceImage> out;
  // A TUM list (rgb.txt: "stamp path") or a EuRoC camera folder (data.csv: "stamp_ns,filename" of
  // data/; stamps in ns, read as seconds).
  const bool euroc = !fs::exists(fs::path(dir) / "rgb.txt") && fs::exists(fs::path(dir) / "data.csv") &&
                     fs::is_directory(fs::path(dir) / "data");
  const fs::path list = fs::path(dir) / (euroc ? "data.csv" : "rgb.txt");
  if (fs::exists(list)) {
    std::ifstream f(list);
    std::string line;
    int n = 0;
    while (std::getline(f, line)) {
      ++n;
      if (line.empty() || line[0] == '#') continue;
      if (euroc) std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream is(line);
      double stamp;
      std::string rel, extra;
      if (!(is >> stamp >> rel) || (is >> extra))
        throw InputError(list.string() + ":" + std::to_string(n) + ": expected 'timestamp filename', got '" + line +
                         "'");
      if (!std::isfinite(stamp))
        throw InputError(list.string() + ":" + std::to_string(n) + ": timestamp must be finite");
      if (euroc) {
        stamp *= 1e-9;
        rel = "data/" + rel;
      }
      if (!out.empty() && stamp <= out.back().stamp)
        throw InputError(list.string() + ":" + std::to_string(n) + ": timestamp " + std::to_string(stamp) +
                         " is not after the previous one");
      out.push_back({stamp, (fs::path(dir) / rel).string()});
    }
  } else {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
      if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    bool numeric = !files.empty();
    std::vector<double> stamps;
    for (const auto& p : files) {
      try {
        size_t used = 0;
        const std::string stem = p.stem().string();
        stamps.push_back(std::stod(stem, &used));
        numeric = numeric && used == stem.size();
      } catch (const std::exception&) {
        numeric = false;
      }
    }
    if (numeric) {
      // Integer names of 16+ digits are nanoseconds (EuRoC's cam0/data/1403636579763555584.png):
      // seconds, on the clock of the IMU log ReadImuSamples reads beside them.
      bool ns = true;
      for (const auto& p : files) {
        const std::string stem = p.stem().string();
        ns = ns && stem.size() >= 16 && stem.find_first_not_of("0123456789") == std::string::npos;
      }
      if (ns)
        for (size_t i = 0; i < files.size(); ++i) stamps[i] = std::stod(files[i].stem().string()) * 1e-9;
      std::vector<size_t> order(files.size());
      for (size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return stamps[a] < stamps[b]; });
      for (size_t i : order) out.push_back({stamps[i], files[i].string()});
      for (size_t i = 1; i < out.size(); ++i)
        if (out[i].stamp <= out[i - 1].stamp)
          throw InputError(dir + ": two images have the stamp " + std::to_string(out[i].stamp));
    } else {
      if (!(fps > 0)) throw InputError(dir + ": images are not named by time and fps is not positive");
      for (size_t i = 0; i < files.size(); ++i) out.push_back({static_cast<double>(i) / fps, files[i].string()});
    }
  }
  if (out.empty()) throw InputError(dir + ": no images (.png/.jpg or rgb.txt)");
  return out;
}

namespace {

// The numbers of a line split at commas or whitespace; false when one is not a number.
bool LineNumbers(const std::string& line, std::vector<double>* out) {
  std::string text = line;
  std::replace(text.begin(), text.end(), ',', ' ');
  std::istringstream is(text);
  out->clear();
  std::string tok;
  while (is >> tok) {
    try {
      std::size_t used = 0;
      out->push_back(std::stod(tok, &used));
      if (used != tok.size()) return false;
    } catch (const std::exception&) {
      if (tok == "nan" || tok == "-nan") {
        out->push_back(std::nan(""));
        continue;
      }
      return false;
    }
  }
  return true;
}

// Calls row(numbers, where) for every data line of a log (blank lines and '#' comments skipped);
// a line that does not parse, has fewer than `min_fields` numbers, or whose first number (the
// stamp) is not after the last one's is an InputError naming file:line.
template <class Row>
void ReadLog(const std::string& path, std::size_t min_fields, Row row) {
  std::ifstream f(path);
  if (!f) throw InputError(path + ": cannot be read");
  std::string line;
  std::vector<double> v;
  double last = -std::numeric_limits<double>::infinity();
  for (int n = 1; std::getline(f, line); ++n) {
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + ":" + std::to_string(n);
    if (!LineNumbers(line, &v) || v.size() < min_fields)
      throw InputError(where + ": expected " + std::to_string(min_fields) + " numbers, got '" + line + "'");
    if (!std::isfinite(v[0]) || v[0] <= last) throw InputError(where + ": the stamp must increase (" + line + ")");
    last = v[0];
    row(v, where);
  }
}

}  // namespace

std::vector<ImuSample> ReadImuSamples(const std::string& path) {
  std::vector<ImuSample> out;
  std::ifstream probe(path);
  std::string first;
  while (std::getline(probe, first) && (first.empty() || first[0] == '#')) {
  }
  const double divisor = first.find(',') != std::string::npos ? 1e9 : 1.0;  // EuRoC: ns
  ReadLog(path, 7, [&](const std::vector<double>& v, const std::string& where) {
    for (std::size_t i = 1; i < 7; ++i)
      if (!std::isfinite(v[i])) throw InputError(where + ": not finite");
    out.push_back({v[0] / divisor, Eigen::Vector3d(v[1], v[2], v[3]), Eigen::Vector3d(v[4], v[5], v[6])});
  });
  return out;
}

std::vector<DvlSample> ReadDvlSamples(const std::string& path) {
  std::vector<DvlSample> out;
  ReadLog(path, 5, [&](const std::vector<double>& v, const std::string& where) {
    DvlSample d;
    d.stamp = v[0];
    d.valid = v[1] > 0.5;
    if (d.valid) {
      d.velocity = Eigen::Vector3d(v[2], v[3], v[4]);
      if (!d.velocity.allFinite()) throw InputError(where + ": a valid reading's velocity must be finite");
    }
    out.push_back(d);
  });
  return out;
}

std::optional<Eigen::Isometry3d> ReadCameraMount(const std::string& manifest_path) {
  YAML::Node y;
  try {
    y = YAML::LoadFile(manifest_path);  // JSON is YAML
  } catch (const YAML::BadFile&) {
    throw InputError(manifest_path + ": cannot be read");
  } catch (const YAML::Exception& e) {
    throw InputError(manifest_path + ": not valid JSON: " + e.what());
  }
  if (const YAML::Node T = y["T_BS"]) {  // EuRoC's cam0/sensor.yaml: the sensor in the body frame
    const YAML::Node d = T["data"];
    if (!d || !d.IsSequence() || d.size() != 16) throw InputError(manifest_path + ": T_BS.data must hold 16 numbers");
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = Number(d[static_cast<std::size_t>(4 * r + c)], manifest_path, "T_BS.data");
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    if (!(R.transpose() * R).isIdentity(1e-6) || R.determinant() < 0.0 ||
        !M.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
      throw InputError(manifest_path + ": T_BS must be a rigid transform");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    X.translation() = M.topRightCorner<3, 1>();
    return X;
  }
  const YAML::Node cam = y["camera"];
  if (!cam || !cam["mount_xyz_m"] || !cam["mount_quaternion_xyzw"]) return std::nullopt;
  if (cam["mount_known"] && !cam["mount_known"].as<bool>(false)) return std::nullopt;
  const YAML::Node p = cam["mount_xyz_m"], q = cam["mount_quaternion_xyzw"];
  if (!p.IsSequence() || p.size() != 3 || !q.IsSequence() || q.size() != 4)
    throw InputError(manifest_path + ": camera.mount_xyz_m needs 3 numbers and camera.mount_quaternion_xyzw 4");
  Eigen::Vector3d t;
  Eigen::Vector4d xyzw;
  for (int i = 0; i < 3; ++i) t[i] = Number(p[i], manifest_path, "camera.mount_xyz_m");
  for (int i = 0; i < 4; ++i) xyzw[i] = Number(q[i], manifest_path, "camera.mount_quaternion_xyzw");
  if (std::abs(xyzw.norm() - 1.0) > 1e-6)
    throw InputError(manifest_path + ": camera.mount_quaternion_xyzw must be a unit quaternion");
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(xyzw[3], xyzw[0], xyzw[1], xyzw[2]).toRotationMatrix();
  X.translation() = t;
  return X;
}

}  // namespace unav::localization

#include "unav_scene/camera.hpp"

#include <cmath>

#include "unav_scene/errors.hpp"
#include "yaml_util.hpp"

namespace unav::scene {

Eigen::Matrix3d CameraModel::K() const {
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

CameraModel CameraModel::from_hfov(const std::string& name, int width, int height, double hfov_rad) {
  if (!(hfov_rad > 0.0 && hfov_rad < M_PI))
    throw ConfigError("camera '" + name + "': hfov must be in (0, 180) deg (got " +
                      std::to_string(hfov_rad * 180.0 / M_PI) + " deg)");
  CameraModel c;
  c.name = name;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * hfov_rad);
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

void CameraModel::validate(const std::string& where) const {
  const std::string pre = where + ": camera '" + name + "': ";
  if (width <= 0 || height <= 0 || width > 8192 || height > 8192)
    throw ConfigError(pre + "width/height must be in 1..8192 (got " + std::to_string(width) + "x" +
                      std::to_string(height) + ")");
  if (!(fx > 0.0) || !(fy > 0.0))
    throw ConfigError(pre + "focal length / field of view must be positive (fx=" + std::to_string(fx) +
                      ", fy=" + std::to_string(fy) + ")");
  if (!std::isfinite(cx) || !std::isfinite(cy)) throw ConfigError(pre + "cx/cy not finite");
  if (!(near_m > 0.0 && far_m > near_m)) throw ConfigError(pre + "need 0 < near_m < far_m");
  if (!(noise_stddev >= 0.0)) throw ConfigError(pre + "noise_stddev must be >= 0");
  if (!(exposure > 0.0)) throw ConfigError(pre + "exposure must be > 0");
}

std::vector<CameraModel> load_cameras(const std::string& path) {
  using namespace detail;
  YamlCtx c{path};
  const YAML::Node root = load_yaml_file(path);
  check_keys(c, root, "", {"cameras", "description"});
  const YAML::Node list = root["cameras"];
  if (!list || !list.IsSequence()) c.fail("cameras", "expected a list of cameras");
  std::vector<CameraModel> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string p = "cameras[" + std::to_string(i) + "]";
    check_keys(c, n, p,
               {"name", "mount", "width", "height", "hfov_deg", "intrinsics", "distortion", "noise_stddev", "exposure",
                "near_m", "far_m"});
    const std::string name = get_string(c, n, p, "name", "");
    if (name.empty()) c.fail(join_key(p, "name"), "missing camera name");
    const int w = static_cast<int>(get_double(c, n, p, "width", 0));
    const int h = static_cast<int>(get_double(c, n, p, "height", 0));
    if (w <= 0 || h <= 0) c.fail(p + " (" + name + ")", "width and height must be positive");
    CameraModel cam;
    if (n["intrinsics"]) {
      const YAML::Node k = n["intrinsics"];
      const std::string kp = join_key(p, "intrinsics");
      check_keys(c, k, kp, {"fx", "fy", "cx", "cy"});
      cam.name = name;
      cam.width = w;
      cam.height = h;
      cam.fx = get_double(c, k, kp, "fx", 0);
      cam.fy = get_double(c, k, kp, "fy", cam.fx);
      cam.cx = get_double(c, k, kp, "cx", 0.5 * (w - 1));
      cam.cy = get_double(c, k, kp, "cy", 0.5 * (h - 1));
      if (!(cam.fx > 0) || !(cam.fy > 0)) c.fail(join_key(kp, "fx"), "focal lengths must be positive");
    } else {
      const double hfov_deg = get_double(c, n, p, "hfov_deg", -1.0);
      if (!n["hfov_deg"]) c.fail(join_key(p, "hfov_deg"), "need hfov_deg or intrinsics");
      if (!(hfov_deg > 0.0 && hfov_deg < 180.0))
        c.fail(join_key(p, "hfov_deg"), "field of view must be in (0, 180) deg (got " + std::to_string(hfov_deg) + ")");
      cam = CameraModel::from_hfov(name, w, h, hfov_deg * M_PI / 180.0);
    }
    if (const YAML::Node m = n["mount"]) {
      const std::string mp = join_key(p, "mount");
      check_keys(c, m, mp, {"xyz_m", "rpy_deg", "frame"});
      const std::string frame = get_string(c, m, mp, "frame", "base_link_frd");
      if (frame != "base_link_frd") c.fail(join_key(mp, "frame"), "only base_link_frd is supported");
      const Eigen::Vector3d xyz = get_vec<3>(c, m, mp, "xyz_m", Eigen::Vector3d::Zero());
      const Eigen::Vector3d rpy = get_vec<3>(c, m, mp, "rpy_deg", Eigen::Vector3d::Zero()) * M_PI / 180.0;
      // rpy orients the camera body (x = optical axis, FRD-like); optical = that * fixed R.
      cam.X_BC = pose_from_xyz_rpy(xyz, rpy);
      cam.X_BC.linear() = cam.X_BC.linear() * R_camera_body_to_optical();
    } else {
      cam.X_BC.linear() = R_camera_body_to_optical();
    }
    if (const YAML::Node d = n["distortion"]) {
      const std::string dp = join_key(p, "distortion");
      check_keys(c, d, dp, {"model", "k1", "k2", "p1", "p2", "k3"});
      const std::string model = get_string(c, d, dp, "model", "plumb_bob");
      if (model != "plumb_bob") c.fail(join_key(dp, "model"), "only plumb_bob is supported");
      cam.distortion << get_double(c, d, dp, "k1", 0), get_double(c, d, dp, "k2", 0), get_double(c, d, dp, "p1", 0),
          get_double(c, d, dp, "p2", 0), get_double(c, d, dp, "k3", 0);
    }
    cam.noise_stddev = get_double(c, n, p, "noise_stddev", 0.0);
    cam.exposure = get_double(c, n, p, "exposure", 1.0);
    cam.near_m = get_double(c, n, p, "near_m", cam.near_m);
    cam.far_m = get_double(c, n, p, "far_m", cam.far_m);
    cam.validate(path);
    for (const auto& o : out)
      if (o.name == name) c.fail(join_key(p, "name"), "duplicate camera name '" + name + "'");
    out.push_back(cam);
  }
  return out;
}

std::vector<CameraModel> default_cameras() {
  CameraModel front = CameraModel::from_hfov("front", 640, 480, 80.0 * M_PI / 180.0);
  front.X_BC = pose_from_xyz_rpy({0.21, 0.0, 0.05}, {0.0, 0.0, 0.0});
  front.X_BC.linear() = front.X_BC.linear() * R_camera_body_to_optical();
  CameraModel down = CameraModel::from_hfov("down", 320, 180, 90.0 * M_PI / 180.0);
  down.X_BC = pose_from_xyz_rpy({0.10, 0.0, 0.12}, {0.0, -M_PI / 2, 0.0});
  down.X_BC.linear() = down.X_BC.linear() * R_camera_body_to_optical();
  return {front, down};
}

CameraModel load_camera(const std::string& path, const std::string& name) {
  std::string names;
  for (const auto& c : load_cameras(path)) {
    if (c.name == name) return c;
    names += (names.empty() ? "" : ", ") + c.name;
  }
  throw ConfigError(path, "cameras", name, "no camera of that name (cameras: " + names + ")");
}

}  // namespace unav::scene

#include "unav_scene/camera.hpp"

#include <cmath>

#include "unav_common/config.hpp"
#include "unav_common/frames.hpp"
#include "unav_scene/errors.hpp"

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

namespace {

// The camera YAML's schema (layout: config/sensors/bluerov2_cameras.yaml). Zero/negative
// defaults mark "not given" where the loader derives a value (fy = fx, centred principal point,
// focal length from hfov_deg).
struct IntrinsicsSpec {
  double fx = 0, fy = 0, cx = -1, cy = -1;
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("fx", &fx).Min(0.0).Unit("px").Doc("focal length (required with intrinsics)"));
    a->Visit(Field("fy", &fy).Min(0.0).Unit("px").Doc("0 = fx"));
    a->Visit(Field("cx", &cx).Min(-1.0).Unit("px").Doc("-1 = (width - 1) / 2"));
    a->Visit(Field("cy", &cy).Min(-1.0).Unit("px").Doc("-1 = (height - 1) / 2"));
  }
};

struct MountSpec {
  Eigen::Vector3d xyz_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();
  std::string frame = common::kBodyFrame;
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("xyz_m", &xyz_m).Unit("m").Doc("position on the body"));
    a->Visit(Field("rpy_deg", &rpy_deg)
                 .Unit("deg")
                 .Doc("camera body (x = optical axis) roll, pitch, yaw; [0, -90, 0] looks down"));
    a->Visit(Field("frame", &frame).OneOf({common::kBodyFrame}).Doc("parent frame"));
  }
};

struct DistortionSpec {
  std::string model = "plumb_bob";
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("model", &model).OneOf({"plumb_bob"}).Doc("OpenCV radial-tangential"));
    a->Visit(Field("k1", &k1));
    a->Visit(Field("k2", &k2));
    a->Visit(Field("p1", &p1));
    a->Visit(Field("p2", &p2));
    a->Visit(Field("k3", &k3));
  }
};

struct CameraSpec {
  std::string name;
  MountSpec mount;
  int width = 0, height = 0;
  double hfov_deg = 0.0;
  IntrinsicsSpec intrinsics;
  DistortionSpec distortion;
  double noise_stddev = 0.0;
  double exposure = 1.0;
  double near_m = 0.05, far_m = 200.0;
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("name", &name).Doc("camera name (topics camera/<name>/..., frame <name>_optical); required"));
    a->Visit(Field("mount", &mount).Doc("pose on base_link_frd"));
    a->Visit(Field("width", &width).Range(0, 8192).Unit("px").Doc("required"));
    a->Visit(Field("height", &height).Range(0, 8192).Unit("px").Doc("required"));
    a->Visit(
        Field("hfov_deg", &hfov_deg).Min(0.0).Below(180.0).Unit("deg").Doc("horizontal field of view, or intrinsics"));
    a->Visit(Field("intrinsics", &intrinsics).Doc("pinhole intrinsics instead of hfov_deg"));
    a->Visit(Field("distortion", &distortion).Doc("lens distortion; all zero = none"));
    a->Visit(Field("noise_stddev", &noise_stddev).Min(0.0).Doc("additive Gaussian noise, fraction of full scale"));
    a->Visit(Field("exposure", &exposure).Above(0.0).Doc("linear gain before sRGB encoding"));
    a->Visit(Field("near_m", &near_m).Above(0.0).Unit("m").Doc("near clip plane"));
    a->Visit(Field("far_m", &far_m).Above(0.0).Unit("m").Doc("far clip plane"));
  }
};

struct CameraFile {
  std::string description;
  std::vector<CameraSpec> cameras;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(common::Field("description", &description));
    a->Visit(common::Field("cameras", &cameras).Doc("the cameras of the vehicle"));
  }
};

CameraModel make_camera(const CameraSpec& s, const std::string& file, const std::string& key) {
  if (s.name.empty()) throw ConfigError(file, key + ".name", "", "a camera needs a name");
  if (s.width <= 0 || s.height <= 0)
    throw ConfigError(file, key, std::to_string(s.width) + "x" + std::to_string(s.height),
                      "width and height are required and positive");
  CameraModel cam;
  if (s.intrinsics.fx > 0.0) {
    cam.name = s.name;
    cam.width = s.width;
    cam.height = s.height;
    cam.fx = s.intrinsics.fx;
    cam.fy = s.intrinsics.fy > 0.0 ? s.intrinsics.fy : cam.fx;
    cam.cx = s.intrinsics.cx >= 0.0 ? s.intrinsics.cx : 0.5 * (s.width - 1);
    cam.cy = s.intrinsics.cy >= 0.0 ? s.intrinsics.cy : 0.5 * (s.height - 1);
  } else {
    if (!(s.hfov_deg > 0.0))
      throw ConfigError(file, key + ".hfov_deg", std::to_string(s.hfov_deg),
                        "need hfov_deg in (0, 180) or intrinsics with fx > 0");
    cam = CameraModel::from_hfov(s.name, s.width, s.height, s.hfov_deg * M_PI / 180.0);
  }
  // rpy orients the camera body (x = optical axis, FRD-like); optical = that * fixed R.
  cam.X_BC = pose_from_xyz_rpy(s.mount.xyz_m, s.mount.rpy_deg * M_PI / 180.0);
  cam.X_BC.linear() = cam.X_BC.linear() * R_camera_body_to_optical();
  const DistortionSpec& d = s.distortion;
  cam.distortion << d.k1, d.k2, d.p1, d.p2, d.k3;
  cam.noise_stddev = s.noise_stddev;
  cam.exposure = s.exposure;
  cam.near_m = s.near_m;
  cam.far_m = s.far_m;
  cam.validate(file);
  return cam;
}

}  // namespace

std::vector<CameraModel> load_cameras(const std::string& path) {
  const auto file = common::LoadYamlFile<CameraFile>(path);
  if (file.cameras.empty()) throw ConfigError(path, "cameras", "", "expected a non-empty list of cameras");
  std::vector<CameraModel> out;
  for (std::size_t i = 0; i < file.cameras.size(); ++i) {
    const std::string key = "cameras[" + std::to_string(i) + "]";
    out.push_back(make_camera(file.cameras[i], path, key));
    for (std::size_t j = 0; j + 1 < out.size(); ++j)
      if (out[j].name == out.back().name)
        throw ConfigError(path, key + ".name", out.back().name, "duplicate camera name");
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

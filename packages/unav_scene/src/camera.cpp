#include "unav_scene/camera.hpp"

#include <Eigen/Dense>
#include <algorithm>
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

Eigen::Vector3d CameraPort::to_water(const Eigen::Vector3d& d_air) const {
  Eigen::Vector3d d = d_air.normalized();
  const double eta = air_index / water_index;
  if (type == Type::kFlat) {
    // Snell at interfaces normal to the optical axis: the transverse components scale by
    // n_air / n_water (parallel glass faces cancel out).
    const double tx = eta * d.x(), ty = eta * d.y();
    return {tx, ty, std::sqrt(std::max(0.0, 1.0 - tx * tx - ty * ty))};
  }
  if (type == Type::kDome) {
    // From the pupil at (0, 0, offset) of the dome centre to the sphere, refract with the
    // outward normal there (thin glass).
    const Eigen::Vector3d P(0.0, 0.0, dome_offset_m);
    const double b = P.dot(d), c = P.squaredNorm() - dome_radius_m * dome_radius_m;
    const double t = -b + std::sqrt(std::max(0.0, b * b - c));
    const Eigen::Vector3d n = (P + t * d) / dome_radius_m;
    const double cos_i = d.dot(n);
    const double k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    return (eta * d + (std::sqrt(std::max(0.0, k)) - eta * cos_i) * n).normalized();
  }
  return d;
}

namespace {
// Normalized undistorted coordinates of normalized distorted ones (plumb_bob, fixed point).
Eigen::Vector2d undistort(const Eigen::Matrix<double, 5, 1>& D, const Eigen::Vector2d& xd) {
  Eigen::Vector2d x = xd;
  for (int i = 0; i < 50; ++i) {
    const double r2 = x.squaredNorm();
    const double radial = 1.0 + D[0] * r2 + D[1] * r2 * r2 + D[4] * r2 * r2 * r2;
    const Eigen::Vector2d tang(2.0 * D[2] * x.x() * x.y() + D[3] * (r2 + 2.0 * x.x() * x.x()),
                               D[2] * (r2 + 2.0 * x.y() * x.y()) + 2.0 * D[3] * x.x() * x.y());
    x = (xd - tang) / radial;
  }
  return x;
}
}  // namespace

CameraModel CameraModel::water_equivalent() const {
  if (!port.refracts()) return *this;
  // Paraxial magnification: a ray 1e-4 rad off the axis in air, and in water.
  const double eps = 1e-4;
  const Eigen::Vector3d w0 = port.to_water({eps, 0.0, 1.0});
  const double m = eps / (w0.x() / w0.z());
  CameraModel out = *this;
  out.port = CameraPort{};
  out.fx = fx * m;
  out.fy = fy * m;
  const double p1 = m * distortion[2], p2 = m * distortion[3];
  // Radial terms by least squares over a grid of the image's pixels.
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> rhs;
  for (int j = 0; j <= 30; ++j)
    for (int i = 0; i <= 40; ++i) {
      const double u = (width - 1) * i / 40.0, v = (height - 1) * j / 30.0;
      const Eigen::Vector2d xd((u - cx) / fx, (v - cy) / fy);
      const Eigen::Vector2d xa = undistort(distortion, xd);
      const Eigen::Vector3d dw = port.to_water({xa.x(), xa.y(), 1.0});
      const Eigen::Vector2d xw(dw.x() / dw.z(), dw.y() / dw.z());
      const double r2 = xw.squaredNorm();
      const Eigen::Vector2d target = xd / m;  // the pixel in water-normalized coordinates
      const Eigen::Vector2d tang(2.0 * p1 * xw.x() * xw.y() + p2 * (r2 + 2.0 * xw.x() * xw.x()),
                                 p1 * (r2 + 2.0 * xw.y() * xw.y()) + 2.0 * p2 * xw.x() * xw.y());
      for (int c = 0; c < 2; ++c) {
        rows.emplace_back(xw[c] * r2, xw[c] * r2 * r2, xw[c] * r2 * r2 * r2);
        rhs.push_back(target[c] - tang[c] - xw[c]);
      }
    }
  Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    A.row(static_cast<Eigen::Index>(k)) = rows[k].transpose();
    b[static_cast<Eigen::Index>(k)] = rhs[k];
  }
  const Eigen::Vector3d kr = A.colPivHouseholderQr().solve(b);
  out.distortion << kr[0], kr[1], p1, p2, kr[2];
  return out;
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

double CameraLens::blur_diameter_px(double z_m, double fx_px) const {
  if (!defocus() || !(z_m > 0.0)) return 0.0;
  const double aperture = 1e-3 * focal_length_mm / f_number;
  return fx_px * aperture * std::abs(1.0 / focus_distance_m - 1.0 / z_m);
}

Eigen::Vector3d CameraWhiteBalance::gains_for(const Eigen::Vector3d& E_d) const {
  if (mode == "manual") return gains;
  if (mode != "auto") return Eigen::Vector3d::Ones();
  Eigen::Vector3d g;
  for (int i = 0; i < 3; ++i) g[i] = std::clamp(E_d[1] / std::max(E_d[i], 1e-30), 1.0 / max_gain, max_gain);
  g[1] = 1.0;
  return g;
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
  if (!(shot_noise >= 0.0 && shot_noise <= 1.0)) throw ConfigError(pre + "shot_noise must be in [0, 1]");
  if (!(vignetting >= 0.0 && vignetting <= 1.0)) throw ConfigError(pre + "vignetting must be in [0, 1]");
  if (!(exposure_time_s >= 0.0 && exposure_time_s <= 1.0))
    throw ConfigError(pre + "exposure_time_s must be in [0, 1] s");
  if (!(lens.f_number >= 0.0 && lens.f_number <= 64.0)) throw ConfigError(pre + "lens.f_number must be in [0, 64]");
  if (lens.defocus() && !(lens.focal_length_mm > 0.0 && lens.focus_distance_m > 1e-3 * lens.focal_length_mm))
    throw ConfigError(pre + "lens: need focal_length_mm > 0 and focus_distance_m beyond the focal length");
  if (!(std::abs(lens.lateral_chromatic) <= 0.05))
    throw ConfigError(pre + "lens.lateral_chromatic must be in [-0.05, 0.05]");
  if (white_balance.mode != "off" && white_balance.mode != "manual" && white_balance.mode != "auto")
    throw ConfigError(pre + "white_balance.mode must be one of off, manual, auto (got '" + white_balance.mode + "')");
  if (!(white_balance.gains.minCoeff() > 0.0 && white_balance.gains.maxCoeff() <= 64.0))
    throw ConfigError(pre + "white_balance.gains must be in (0, 64]");
  if (!(white_balance.max_gain >= 1.0 && white_balance.max_gain <= 64.0))
    throw ConfigError(pre + "white_balance.max_gain must be in [1, 64]");
  if (jpeg_quality < 0 || jpeg_quality > 100)
    throw ConfigError(pre + "jpeg_quality must be in 0..100 (0: no compression), got " + std::to_string(jpeg_quality));
  if (!(port.water_index >= 1.0 && port.water_index <= 2.0))
    throw ConfigError(pre + "port.water_index must be in [1, 2]");
  if (!(port.air_index >= 1.0 && port.air_index <= 2.0)) throw ConfigError(pre + "port.air_index must be in [1, 2]");
  if (!(port.glass_thickness_m >= 0.0)) throw ConfigError(pre + "port.glass_thickness_m must be >= 0");
  if (!(port.air_gap_m >= 0.0)) throw ConfigError(pre + "port.air_gap_m must be >= 0");
  if (!(port.dome_radius_m > 0.0)) throw ConfigError(pre + "port.dome_radius_m must be > 0");
  if (!(std::abs(port.dome_offset_m) < port.dome_radius_m))
    throw ConfigError(pre + "port.dome_offset_m must be inside the dome (|offset| < dome_radius_m)");
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

struct PortSpec {
  std::string type = "none";
  double water_index = 1.34, air_index = 1.0;
  double glass_thickness_m = 0.0, air_gap_m = 0.0;
  double dome_radius_m = 0.05, dome_offset_m = 0.0;
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("type", &type).OneOf({"none", "flat", "dome"}).Doc("housing port the camera looks through"));
    a->Visit(Field("water_index", &water_index).Range(1.0, 2.0).Doc("refractive index of the water"));
    a->Visit(Field("air_index", &air_index).Range(1.0, 2.0).Doc("refractive index inside the housing"));
    a->Visit(Field("glass_thickness_m", &glass_thickness_m).Min(0.0).Unit("m").Doc("flat port glass"));
    a->Visit(Field("air_gap_m", &air_gap_m).Min(0.0).Unit("m").Doc("flat port: pupil to glass"));
    a->Visit(Field("dome_radius_m", &dome_radius_m).Above(0.0).Unit("m").Doc("dome port radius"));
    a->Visit(Field("dome_offset_m", &dome_offset_m).Unit("m").Doc("pupil offset from the dome centre (+ = outwards)"));
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
  double shot_noise = 0.0;
  double exposure = 1.0;
  double vignetting = 0.0;
  double exposure_time_s = 0.0;
  PortSpec port;
  CameraLens lens;
  CameraWhiteBalance white_balance;
  int jpeg_quality = 0;
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
    a->Visit(
        Field("shot_noise", &shot_noise).Range(0.0, 1.0).Doc("shot noise variance per unit signal (1 / full well)"));
    a->Visit(Field("exposure", &exposure).Above(0.0).Doc("linear gain before sRGB encoding"));
    a->Visit(Field("vignetting", &vignetting).Range(0.0, 1.0).Doc("share of the cos^4 falloff"));
    a->Visit(Field("exposure_time_s", &exposure_time_s)
                 .Range(0.0, 1.0)
                 .Unit("s")
                 .Doc("exposure ending at the stamp: motion blur from the vehicle's velocity; 0 = none"));
    a->Visit(Field("port", &port).Doc("housing port (flat / dome); K and distortion are in air"));
    a->Visit(Field("lens", &lens).Doc("depth of field and lateral colour"));
    a->Visit(Field("white_balance", &white_balance).Doc("white balance: off, manual gains or auto"));
    a->Visit(Field("jpeg_quality", &jpeg_quality).Range(0, 100).Doc("JPEG compression of the image; 0 = none"));
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
  cam.shot_noise = s.shot_noise;
  cam.exposure = s.exposure;
  cam.vignetting = s.vignetting;
  cam.exposure_time_s = s.exposure_time_s;
  cam.port.type = s.port.type == "flat"   ? CameraPort::Type::kFlat
                  : s.port.type == "dome" ? CameraPort::Type::kDome
                                          : CameraPort::Type::kNone;
  cam.port.water_index = s.port.water_index;
  cam.port.air_index = s.port.air_index;
  cam.port.glass_thickness_m = s.port.glass_thickness_m;
  cam.port.air_gap_m = s.port.air_gap_m;
  cam.port.dome_radius_m = s.port.dome_radius_m;
  cam.port.dome_offset_m = s.port.dome_offset_m;
  if (cam.port.type == CameraPort::Type::kDome && !(std::abs(cam.port.dome_offset_m) < cam.port.dome_radius_m))
    throw ConfigError(file, key + ".port.dome_offset_m", std::to_string(cam.port.dome_offset_m),
                      "must be inside the dome (|offset| < dome_radius_m)");
  cam.lens = s.lens;
  cam.white_balance = s.white_balance;
  cam.jpeg_quality = s.jpeg_quality;
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

CameraModel scale_camera(const CameraModel& camera, int width, int height) {
  if (width <= 0 || height <= 0 || (width == camera.width && height == camera.height)) return camera;
  CameraModel c = camera;
  const double sx = static_cast<double>(width) / camera.width, sy = static_cast<double>(height) / camera.height;
  c.width = width;
  c.height = height;
  c.fx *= sx;
  c.fy *= sy;
  // Pixel centres: u' + 0.5 = sx (u + 0.5).
  c.cx = sx * (camera.cx + 0.5) - 0.5;
  c.cy = sy * (camera.cy + 0.5) - 0.5;
  return c;
}

}  // namespace unav::scene

// Camera models loaded from config/sensors/*.yaml.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_scene/frames.hpp"

namespace unav::scene {

/// The lens beyond the pinhole: depth of field of a thin lens and lateral chromatic aberration.
/// Distances are those of the water side (behind a flat port the paraxial image of a point at z
/// lies at z / n and the water-side focal length is n times the in-air one: the blur is the same).
struct CameraLens {
  double f_number = 0.0;           ///< 0 = a pinhole: everything in focus
  double focal_length_mm = 4.0;    ///< physical focal length: with f_number, the aperture diameter
  double focus_distance_m = 2.0;   ///< distance of the sharp plane along the optical axis
  double lateral_chromatic = 0.0;  ///< the red image magnified by 1 + k, the blue by 1 - k (green: 1)

  bool defocus() const { return f_number > 0.0; }
  /// Diameter [px] of the blur disc (circle of confusion) of a point at depth z_m (along the optical
  /// axis) for a camera of calibrated focal length fx_px (lens-to-sensor distance over the pixel
  /// pitch, with the lens focused at focus_distance_m): fx_px A |1 / z_f - 1 / z|, A = f / N the
  /// aperture; 0 without defocus.
  double blur_diameter_px(double z_m, double fx_px) const;

  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("f_number", &f_number).Range(0.0, 64.0).Doc("aperture f/N; 0 = pinhole (no depth of field)"));
    a->Visit(Field("focal_length_mm", &focal_length_mm).Above(0.0).Max(1000.0).Unit("mm").Doc("physical focal length"));
    a->Visit(Field("focus_distance_m", &focus_distance_m).Above(0.0).Unit("m").Doc("sharp plane, along the axis"));
    a->Visit(Field("lateral_chromatic", &lateral_chromatic)
                 .Range(-0.05, 0.05)
                 .Doc("lateral colour: red magnified 1 + k, blue 1 - k, about the principal point"));
  }
};

/// White balance: per-channel gains on the linear signal before the encoding, as a camera applies
/// them to its raw RGB. manual: `gains`; auto: re-metered every frame for the ambient light at the
/// camera's depth (what a pilot's white slate at that depth gives: the downwelling irradiance's
/// colour made grey, green kept), each gain within [1 / max_gain, max_gain]; off: none.
struct CameraWhiteBalance {
  std::string mode = "off";
  Eigen::Vector3d gains{1.0, 1.0, 1.0};
  double max_gain = 8.0;

  /// The gains for downwelling irradiance E_d (RGB) at the camera: `gains` (manual), green / E_d
  /// clamped (auto), ones (off).
  Eigen::Vector3d gains_for(const Eigen::Vector3d& E_d) const;

  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("mode", &mode).OneOf({"off", "manual", "auto"}).Doc("white balance of the linear signal"));
    a->Visit(Field("gains", &gains).Above(0.0).Max(64.0).Doc("manual: R G B gains"));
    a->Visit(Field("max_gain", &max_gain).Min(1.0).Max(64.0).Doc("auto: gains within [1 / max, max]"));
  }
};

/// The housing port a camera looks through (REFERENCE: flat ports magnify by n_water / n_air
/// and add pincushion distortion; a dome centred on the entrance pupil changes nothing).
/// Only ray directions are modelled: the ray's lateral offset in the glass and air gap (a few
/// millimetres) is neglected, so the port acts as a fixed, depth-independent warp.
struct CameraPort {
  enum class Type { kNone, kFlat, kDome };
  Type type = Type::kNone;
  double water_index = 1.34;  ///< refractive index of sea water (1.33 fresh .. 1.345)
  double air_index = 1.0;     ///< inside the housing
  /// Flat port: glass and air gap between the entrance pupil and the glass [m] (parallel faces:
  /// they shift rays sideways but do not turn them; validated, reported, not imaged).
  double glass_thickness_m = 0.0;
  double air_gap_m = 0.0;
  /// Dome port (thin glass): radius and the entrance pupil's offset from the dome centre
  /// along the optical axis (+ = towards the dome); 0 = centred, no refraction.
  double dome_radius_m = 0.05;
  double dome_offset_m = 0.0;
  bool refracts() const { return type != Type::kNone; }
  /// The water-side direction of a ray that leaves the camera along `d_air` (optical frame,
  /// z forward; any length). Unit vector.
  Eigen::Vector3d to_water(const Eigen::Vector3d& d_air) const;
};

/// Pinhole camera with plumb_bob distortion, mounted on the vehicle body.
/// Pixel convention as OpenCV / ROS CameraInfo: the centre of the top-left pixel is (0, 0),
/// u = fx x/z + cx, v = fy y/z + cy in the optical frame.
struct CameraModel {
  std::string name = "camera";
  Pose X_BC = Pose::Identity();  ///< optical frame C in body frame base_link_frd
  int width = 320;
  int height = 180;
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< [px]
  /// plumb_bob coefficients k1, k2, p1, p2, k3 (OpenCV order); all zero = none.
  Eigen::Matrix<double, 5, 1> distortion = Eigen::Matrix<double, 5, 1>::Zero();
  double noise_stddev = 0.0;  ///< read noise: additive Gaussian, fraction of full scale (0..1)
  /// Shot noise: variance shot_noise * I of the linear signal I (0..1 of full scale), i.e.
  /// 1 / shot_noise photo-electrons at full scale (full-well capacity); 0 = none.
  double shot_noise = 0.0;
  double exposure = 1.0;  ///< linear gain before sRGB encoding
  /// Natural vignetting: the image falls off as 1 - s (1 - cos^4 t), t the in-air field angle
  /// of the pixel; s in [0, 1] (1 = the full cos^4 law).
  double vignetting = 0.0;
  /// Exposure time [s] ending at the frame's stamp: motion blur from the vehicle's velocity
  /// over it (the renderer smears the image along each pixel's motion); 0 = none.
  double exposure_time_s = 0.0;
  CameraPort port;  ///< K and distortion are the in-air camera's; the port refracts its rays
  CameraLens lens;
  CameraWhiteBalance white_balance;
  /// JPEG compression of the 8-bit image (quality 1..100, as a camera streaming MJPEG or a dataset
  /// stored as JPEG: 8 x 8 block artefacts, chroma subsampling); 0 = none.
  int jpeg_quality = 0;
  double near_m = 0.05, far_m = 200.0;

  Eigen::Matrix3d K() const;
  bool has_distortion() const { return distortion.cwiseAbs().maxCoeff() > 0.0; }
  /// The pinhole + plumb_bob model that best describes this camera behind its port as seen
  /// from the water (what CameraInfo publishes and estimators use): focal lengths scaled by the
  /// port's paraxial magnification (n_water / n_air for a flat port) and radial k1, k2, k3
  /// fitted by least squares over the image (the in-air tangential terms kept). Without a
  /// refracting port: *this.
  CameraModel water_equivalent() const;
  /// Build from a horizontal field of view [rad]; fy = fx, principal point at the centre.
  static CameraModel from_hfov(const std::string& name, int width, int height, double hfov_rad);
  /// Throws ConfigError naming the camera and field (non-positive FOV/size, ...).
  void validate(const std::string& where) const;
};

/// Load all cameras of a sensor YAML file (layout: see config/sensors/bluerov2_cameras.yaml).
/// Errors name the file, the camera and the key.
std::vector<CameraModel> load_cameras(const std::string& path);

/// The camera called `name` in a sensor YAML file. Throws ConfigError naming the file, the camera
/// and the cameras the file has when there is none of that name.
CameraModel load_camera(const std::string& path, const std::string& name);

/// The paper's default vehicle: "front" (640x480, 80 deg) and "down" (320x180, 90 deg).
std::vector<CameraModel> default_cameras();

/// The camera scaled to width x height (same field of view; principal point and distortion
/// scaled with the image); itself when width or height is 0 or the size is unchanged.
CameraModel scale_camera(const CameraModel& camera, int width, int height);

}  // namespace unav::scene

// Water optics parameters (REFERENCE.md section 3; Akkaynak & Treibitz 2018 revised model):
//   I_c = J_c exp(-beta_D_c z) + B_inf_c (1 - exp(-beta_B_c z))     (z: range along the ray)
// plus forward scattering (range-dependent blur), lamp in-scattering with a Schlick phase
// function, and sunlight decaying with depth E(d) = E0 exp(-K_d d).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace unav::scene {

/// Per-channel (R, G, B) optical properties of the water. All coefficients in 1/m.
struct WaterModel {
  std::string name = "jerlov_I";
  Eigen::Vector3d beta_D{0.217, 0.040, 0.018};  ///< direct-signal attenuation [1/m]
  Eigen::Vector3d beta_B{0.217, 0.040, 0.018};  ///< backscatter coefficient [1/m]
  Eigen::Vector3d K_d{0.217, 0.040, 0.018};     ///< diffuse downwelling attenuation [1/m]
  /// Veiling light B_inf for unit surface irradiance just below the surface (linear RGB,
  /// 0..1 display units). The effective value at camera depth d is veiling_light_at(d).
  Eigen::Vector3d B_inf{0.02, 0.16, 0.24};
  /// Veiling light seen along a ray with world up-component u (-1 down .. 1 up) is
  /// B_inf (1 + gradient u): water looks brighter towards the surface. 0 = isotropic.
  double veiling_light_gradient = 0.35;
  /// Scattering coefficient b used for in-scattering of lamp light [1/m].
  Eigen::Vector3d b_scatter{0.02, 0.02, 0.01};
  double phase_g = 0.92;  ///< Henyey-Greenstein asymmetry; Schlick k = 1.55g - 0.55g^3
  /// Share of scattered light sent backwards (b_b / b; Petzold's ocean data ~0.019). The
  /// phase function is (1 - f) Schlick(k) + f / (2 pi) over the backward hemisphere: a single
  /// forward lobe with g = 0.92 alone would make lamp backscatter vanish.
  double phase_backscatter_fraction = 0.019;
  /// Forward scattering: fraction of the direct signal blurred per metre of range [1/m] and
  /// blur radius growth [rad per metre of range]; the kernel widens with range.
  double forward_scatter_per_m = 0.02;
  double forward_blur_rad_per_m = 0.0015;
  /// Acoustics (sonar): sound speed (Mackenzie 1981) and absorption (Francois-Garrison 1982)
  /// follow from temperature, salinity and pH (and the sonar's depth).
  double temperature_c = 10.0;  ///< [deg C], -2..40
  double salinity_psu = 35.0;   ///< practical salinity, 0..45
  double ph = 8.0;              ///< 7..9
  /// Refractive index of the water (Snell's window: the sky is seen within asin(1 / n) of the
  /// zenith, total internal reflection beyond). 1.33 fresh .. 1.345 cold sea water.
  double refractive_index = 1.34;

  /// Effective veiling light for a camera at depth `depth_m` with surface irradiance E0:
  /// B_inf * E0 * exp(-K_d depth) (the ambient light that backscatters also decays).
  Eigen::Vector3d veiling_light_at(double depth_m, const Eigen::Vector3d& E0 = Eigen::Vector3d::Ones()) const;
  /// Schlick phase parameter k = 1.55 g - 0.55 g^3.
  double schlick_k() const { return 1.55 * phase_g - 0.55 * phase_g * phase_g * phase_g; }
  /// Throws ConfigError naming the field on negative/NaN values.
  void validate(const std::string& where) const;
};

/// Names of the built-in Jerlov presets: jerlov_I, jerlov_IA, jerlov_IB, jerlov_II,
/// jerlov_III, jerlov_1C, jerlov_3C, jerlov_5C, jerlov_7C, jerlov_9C.
std::vector<std::string> jerlov_preset_names();

/// Built-in Jerlov preset (beta from REFERENCE.md table, B_inf an estimate). Accepts the
/// name with or without the "jerlov_" prefix ("II", "jerlov_3C"). Throws
/// ConfigError listing valid names.
WaterModel jerlov_preset(const std::string& name);

/// Load a water YAML file (config/water/*.yaml). Either `preset: <name>` optionally
/// followed by overrides, or explicit coefficients. Unknown keys are errors naming the file.
WaterModel load_water_file(const std::string& path);

/// The water a node parameter names: a Jerlov preset ("3C", "jerlov_II") or, when the text
/// holds a '/' or ".yaml", a water YAML file. ConfigError as jerlov_preset / load_water_file.
WaterModel load_water_spec(const std::string& spec);

}  // namespace unav::scene

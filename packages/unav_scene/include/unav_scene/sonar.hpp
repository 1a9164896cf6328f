// Sonar models (config/sensors/*sonar*.yaml) and the acoustics of sea water. No OpenGL: the
// renderer's SonarRenderer images these models; the node, datagen and tests read them here.
//
// Frames. Every sonar has a head frame H on base_link_frd, like a camera body: x = acoustic
// boresight, y right, z down. A forward-looking sonar (FLS) fans its beams across H's x-y plane
// (azimuth, positive to starboard) with the vertical aperture about H's y axis (elevation,
// positive up). A side-scan sonar has two heads, port and starboard: each looks abeam, tilted
// down by `tilt_deg`; its single beam is narrow along track (horizontal_aperture_deg) and wide
// across track (vertical_aperture_deg). A profiling (multibeam) sonar is an FLS fan with a narrow
// vertical aperture, usually mounted looking down with the fan across track; each beam's
// strongest echo gives a range: a profile of points across track.
// Messages use marine_acoustic_msgs' sonar frame S (z forward = H x, x up = -H z, y = H y):
// frame_acoustic() gives X_BS.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "unav_scene/frames.hpp"
#include "unav_scene/water.hpp"

namespace unav::scene {

struct SonarModel {
  enum class Type { kForwardLooking, kSideScan, kProfiling };
  std::string name = "fls";
  Type type = Type::kForwardLooking;
  Pose X_BH = Pose::Identity();  ///< head frame (x boresight, y right, z down) on base_link_frd
  int beams = 256;               ///< FLS: beams across the horizontal aperture; side-scan: 1 per side
  int bins = 512;                ///< range bins between min_range_m and max_range_m
  double horizontal_aperture_rad = 130.0 * M_PI / 180.0;  ///< FLS fan width; side-scan along-track beam width
  double vertical_aperture_rad = 20.0 * M_PI / 180.0;     ///< -3 dB two-way vertical beam width
  double tilt_rad = 0.0;  ///< side-scan: depression of each side's beam axis below horizontal
  double min_range_m = 0.1, max_range_m = 40.0;
  double frequency_hz = 750e3;
  double ping_rate_hz = 10.0;  ///< <= max_ping_rate_hz() (two-way travel time at max range)
  /// Transmission loss one way: spreading_exponent * 10 log10(r) + absorption * r [dB].
  double spreading_exponent = 2.0;  ///< 2 spherical, 1 cylindrical
  /// Time-varied gain, as sonars apply it: + tvg_db_per_decade log10(r) + 2 alpha r [dB]
  /// (30: the standard for the seabed, whose pulse-limited footprint grows as r; 20: exact for a
  /// beam-filling target at normal incidence; 40: point targets). false = raw echo level.
  bool tvg = true;
  double tvg_db_per_decade = 30.0;
  double gain_db = 0.0;            ///< display gain: echo level 0 dB + gain maps to full scale
  double dynamic_range_db = 60.0;  ///< display: full scale - dynamic range maps to 0
  /// Multiplicative speckle I (1 - s + s X) (unav_renderer/sonar_speckle.hpp): X the intensity of a
  /// coherent echo, exponential (Rayleigh amplitude) times a Gamma texture of shape speckle_shape
  /// (K-distributed; contrast sqrt(1 + 2 / shape)), correlated over speckle_grain_beams and
  /// speckle_grain_bins cells (FWHM of its autocorrelation: the beam pattern and the pulse length).
  double speckle = 1.0;
  double speckle_shape = 4.0;        ///< K shape nu; 0 = Rayleigh (no texture)
  double speckle_grain_beams = 1.7;  ///< across beams [beams]
  double speckle_grain_bins = 1.5;   ///< along range [bins]
  double noise_floor_db = -45.0;     ///< additive background, Rayleigh amplitude, mean level re full scale
  /// Side lobes of the receive beam pattern (FLS and profiling fans): every beam also hears, at
  /// each range, the other beams' echoes weighted by the pattern's side-lobe envelope
  /// 10^(sidelobe_db / 10) (1.5 / |d|)^(sidelobe_falloff_db_per_octave / 3.01) at d beams off its
  /// axis (|d| >= 1.5 beams, a line array's first side lobe): the arcs a strong return draws across
  /// the fan at its range. Uniform shading: -13.3 dB, 6 dB/octave; Hann: -31.5 dB, 18 dB/octave.
  bool sidelobes = false;
  double sidelobe_db = -30.0;                   ///< the first side lobe re the main lobe (power, one way)
  double sidelobe_falloff_db_per_octave = 6.0;  ///< the envelope's fall with angle
  int vertical_samples = 0;                     ///< render rows across the vertical aperture; 0 = auto
  int beam_oversample = 2;                      ///< render columns per beam
  std::string data_type = "uint8";              ///< message samples: uint8 (display-coded) or float32 (linear)
  std::string display = "db";                   ///< 8-bit coding: db (gain, dynamic range) or gamma (amplitude^gamma)
  double display_gamma = 0.5;                   ///< gamma coding's exponent on the amplitude

  double detection_db = 10.0;  ///< profiling: a beam's peak this far above its median is a return
  bool side_scan() const { return type == Type::kSideScan; }
  bool profiling() const { return type == Type::kProfiling; }
  /// The type as sonar files and dataset manifests spell it: forward_looking, side_scan, profiling.
  const char* type_name() const;
  int channels() const { return side_scan() ? 2 : beams; }  ///< beams in the message
  double bin_width_m() const { return (max_range_m - min_range_m) / bins; }
  double bin_center_m(int k) const { return min_range_m + (k + 0.5) * bin_width_m(); }
  /// FLS beam k's azimuth (k = 0 is the port edge), uniformly spaced across the aperture.
  double beam_azimuth_rad(int k) const;
  /// The fastest ping rate the two-way travel time allows: c / (2 R_max) (one ping in the water).
  double max_ping_rate_hz(double sound_speed_mps) const { return sound_speed_mps / (2.0 * max_range_m); }
  /// Head frames: FLS one (X_BH), side-scan port then starboard (X_BH yawed -/+90 deg, tilted).
  std::vector<Pose> head_poses() const;
  /// marine_acoustic_msgs sonar frame (z forward, x up) on base_link_frd.
  Pose frame_acoustic() const;
  /// Throws ConfigError naming `where`, the sonar and the key that breaks its rule.
  void validate(const std::string& where) const;
  /// validate() with the error naming `file` and the key path `key` (e.g. "sonars[1]").
  void check(const std::string& file, const std::string& key) const;
};

/// Load all sonars of a sensor YAML file (layout: config/sensors/bluerov2_sonars.yaml). Errors name
/// the file, the sonar and the key; `preset` keys fill the values of a real unit first.
std::vector<SonarModel> load_sonars(const std::string& path);
/// The sonar called `name` in a file (ConfigError listing the file's sonars when there is none).
SonarModel load_sonar(const std::string& path, const std::string& name);
/// Built-in units: oculus_m750d_lf, oculus_m750d_hf, oculus_m1200d_lf, oculus_m1200d_hf,
/// sidescan_900k. ConfigError listing them for another name.
SonarModel sonar_preset(const std::string& name);
std::vector<std::string> sonar_preset_names();

/// Speed of sound in sea water [m/s], Mackenzie (1981): T [deg C], S [PSU], depth [m].
/// Valid 2..30 deg C, 25..40 PSU, 0..8000 m (standard error 0.07 m/s).
double sound_speed_mackenzie(double temperature_c, double salinity_psu, double depth_m);
/// Absorption of sound in sea water [dB/m], Francois & Garrison (1982): boric acid, magnesium
/// sulphate and pure water; 200 Hz..1 MHz, all oceanic conditions.
double absorption_francois_garrison(double frequency_hz, double temperature_c, double salinity_psu, double depth_m,
                                    double ph);
/// The same after Ainslie & McColm (1998), a simpler fit to the same data (cross-check).
double absorption_ainslie_mccolm(double frequency_hz, double temperature_c, double salinity_psu, double depth_m,
                                 double ph);

/// The acoustic state of the water at a depth for a sonar frequency.
struct Acoustics {
  double sound_speed_mps = 1500.0;
  double absorption_db_per_m = 0.0;
};
Acoustics water_acoustics(const WaterModel& water, double depth_m, double frequency_hz);

}  // namespace unav::scene

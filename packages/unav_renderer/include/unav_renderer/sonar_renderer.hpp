// Sonar simulation on the renderer's GL scene (no DDS): forward-looking imaging sonar and
// side-scan sonar (unav_scene/sonar.hpp describes them).
//
// Per ping and per head, the scene is rasterised from the sonar in perspective slices that
// tile the aperture (FLS: <= 32 deg wide each; side-scan: one strip per side). Each sample gives
// the range r of the nearest surface along its ray, the incidence cosine and the material's
// Lambert mu; occluded surfaces never show, so objects cast acoustic shadows. On the CPU each
// sample of solid angle dOmega at elevation el adds the echo
//     E = mu cos(t) dOmega b(el)^2 r^(2 - 2n) 10^(-alpha r / 5)
// (Lambert's law mu cos^2 t times the ensonified area r^2 dOmega / cos t, two-way spreading r^-2n
// and absorption), times the time-varied gain r^(k / 10) 10^(alpha r / 5) when tvg is on (k =
// tvg_db_per_decade), to its beam, spread over the range bins its
// footprint covers (the range difference to its neighbours), so a grazing seabed fills every bin
// it spans. b(el)^2 = exp(-4 ln2 (el / V)^2) is the two-way vertical beam pattern (-3 dB at the
// aperture's edges). Then speckle I (1 - s + s X) and background n0 Y (X, Y ~ Exp(1): Rayleigh
// amplitudes), and the display coding 255 (1 + (10 log10 I + gain) / dynamic_range) clamped.
// Not modelled: multipath, sidelobes, pulse length (one bin = one range cell), the sound
// speed profile (straight rays at the speed at the sonar's depth).
//
// Threading: like Renderer, one thread; it may share the camera renderer's EGL context.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "unav_renderer/egl_context.hpp"
#include "unav_scene/frames.hpp"
#include "unav_scene/sonar.hpp"
#include "unav_scene/world.hpp"

namespace unav::renderer {

struct SonarOptions {
  bool noise = true;       ///< speckle and background noise (false: the mean echo)
  std::uint64_t seed = 1;  ///< noise = f(seed, sonar, sequence)
  EglOptions egl;
};

/// One ping. Samples are row-major by range: [bin * channels + channel], bin 0 nearest.
struct SonarPing {
  std::string sonar;
  bool side_scan = false;
  double stamp_s = 0.0;
  std::uint64_t sequence = 0;
  int channels = 0;  ///< FLS: beams, port to starboard; side-scan: 2 (0 port, 1 starboard)
  int bins = 0;
  std::vector<float> intensity;     ///< linear echo level after tvg and noise (before gain)
  std::vector<std::uint8_t> image;  ///< display-coded 8-bit (gain, dynamic range)
  std::vector<float> ranges_m;      ///< bin centres
  std::vector<float> azimuth_rad;   ///< per channel, + to starboard (side-scan: -pi/2, +pi/2)
  double sound_speed_mps = 0.0;
  double absorption_db_per_m = 0.0;
  double frequency_hz = 0.0;
  unav::scene::Pose X_WS = unav::scene::Pose::Identity();  ///< acoustic frame (z forward, x up) in world
  float at(int bin, int channel) const {
    return intensity[static_cast<std::size_t>(bin) * static_cast<std::size_t>(channels) +
                     static_cast<std::size_t>(channel)];
  }
};

struct SonarTimings {
  double raster_ms = 0;      ///< GL passes and the readback
  double accumulate_ms = 0;  ///< echo accumulation, noise and coding on the CPU
};

class SonarRenderer {
 public:
  /// Builds the world's geometry and the GL programs; `context` null = create one. Validates the
  /// sonars (ConfigError naming the sonar and key). Throws EglError / GlError on GL trouble.
  SonarRenderer(unav::scene::World world, std::vector<unav::scene::SonarModel> sonars, SonarOptions options = {},
                std::shared_ptr<EglContext> context = nullptr);
  ~SonarRenderer();
  SonarRenderer(const SonarRenderer&) = delete;
  SonarRenderer& operator=(const SonarRenderer&) = delete;

  /// One ping of sonar `name` with the body at X_WB (world_ned). std::invalid_argument for an
  /// unknown name.
  SonarPing ping(const unav::scene::Pose& X_WB, const std::string& name, double stamp_s = 0.0);

  void set_world(unav::scene::World world);  ///< new scene, same sonars and context
  /// Moves the world's movable object `name` (Object::movable: another vehicle) to X_WO for the
  /// pings from now on. ConfigError naming it when there is none of that name or X_WO is not finite.
  void set_object_pose(const std::string& name, const unav::scene::Pose& X_WO);
  void set_next_sequence(std::uint64_t sequence);
  const unav::scene::SonarModel& sonar(const std::string& name) const;
  std::vector<std::string> sonar_names() const;
  const unav::scene::World& world() const;
  const EglContext& context() const;
  SonarTimings last_timings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A forward-looking ping as a Cartesian fan (apex at the bottom centre, forward up, starboard
/// right), mono8 `width` pixels wide; outside the fan is 0. Bilinear in range and beam.
struct FanImage {
  int width = 0, height = 0;
  double metres_per_pixel = 0.0;
  std::vector<std::uint8_t> pixels;
};
FanImage fan_image(const SonarPing& ping, int width);

/// Side-scan waterfall: the newest ping on the top row, port samples mirrored on the left half
/// (far range at the left edge), starboard on the right; mono8, 2 * bins wide, `lines` high.
class Waterfall {
 public:
  Waterfall(int bins, int lines);
  void add(const SonarPing& ping);  ///< std::invalid_argument for a ping of another size or an FLS ping
  int width() const { return 2 * bins_; }
  int height() const { return lines_; }
  std::size_t pings() const { return pings_; }
  const std::vector<std::uint8_t>& pixels() const { return pixels_; }

 private:
  int bins_, lines_;
  std::size_t pings_ = 0;
  std::vector<std::uint8_t> pixels_;
};

/// A return of a profiling (or any fan) ping: the range of a beam's strongest echo and its point
/// in the acoustic frame S (z forward, x up, y = starboard) at the beam's azimuth.
struct ProfilePoint {
  int beam = 0;
  double range_m = 0.0;
  Eigen::Vector3d p_S = Eigen::Vector3d::Zero();
  float intensity = 0.0f;  ///< linear echo level of the peak
};
/// Per beam, the strongest echo when it stands detection_db above the beam's median level (its
/// range refined by a parabola through the peak bin's log level and its neighbours': sub-bin);
/// beams without one give no point. std::invalid_argument for a side-scan ping.
std::vector<ProfilePoint> detect_profile(const SonarPing& ping, double detection_db);

/// Write a mono8 image as PNG (ConfigError naming the file when it cannot be written).
void write_png_mono(const std::vector<std::uint8_t>& pixels, int width, int height, const std::string& path);

}  // namespace unav::renderer

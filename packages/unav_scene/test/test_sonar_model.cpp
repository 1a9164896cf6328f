// Sonar configuration and sea-water acoustics (no OpenGL).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "unav_scene/errors.hpp"
#include "unav_scene/sonar.hpp"

using namespace unav::scene;
namespace fs = std::filesystem;

namespace {
const std::string kRoot = UNAV_REPO_ROOT;
constexpr double kDeg = M_PI / 180.0;

std::string write_tmp(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("unav_sonar_" + name + ".yaml");
  std::ofstream(p) << text;
  return p.string();
}

// The error of loading `body` (the sonar's keys), or "" when it loads.
std::string load_error(const std::string& body) {
  const std::string path = write_tmp("bad", "sonars:\n  - name: s\n" + body);
  try {
    load_sonars(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Acoustics, MackenzieCheckValue) {
  // Mackenzie (1981) gives 1550.744 m/s at 25 deg C, 35 PSU, 1000 m as its check value.
  EXPECT_NEAR(sound_speed_mackenzie(25.0, 35.0, 1000.0), 1550.744, 1e-3);
  // Warmer, saltier and deeper water is faster.
  EXPECT_GT(sound_speed_mackenzie(20.0, 35.0, 10.0), sound_speed_mackenzie(10.0, 35.0, 10.0));
  EXPECT_GT(sound_speed_mackenzie(10.0, 38.0, 10.0), sound_speed_mackenzie(10.0, 30.0, 10.0));
}

TEST(Acoustics, FrancoisGarrisonAgreesWithAinslieMcColm) {
  // Two independent fits to the same measurements: they agree within ~10% over the imaging
  // sonar band (100 kHz..1 MHz) and shallow oceanic conditions; 20% leaves room for the fits'
  // own scatter, not for a wrong coefficient (those are factors of 10).
  for (double f : {100e3, 300e3, 750e3, 1.0e6})
    for (double T : {4.0, 10.0, 20.0})
      for (double D : {0.0, 100.0}) {
        const double fg = absorption_francois_garrison(f, T, 35.0, D, 8.0);
        const double am = absorption_ainslie_mccolm(f, T, 35.0, D, 8.0);
        EXPECT_NEAR(fg / am, 1.0, 0.2) << f << " Hz, " << T << " C, " << D << " m";
      }
  // Absorption rises with frequency: ~0.2 dB/m at 750 kHz, ~0.03 dB/m at 100 kHz (10 deg C).
  const double a750 = absorption_francois_garrison(750e3, 10.0, 35.0, 10.0, 8.0);
  EXPECT_GT(a750, 0.15);
  EXPECT_LT(a750, 0.3);
  EXPECT_LT(absorption_francois_garrison(100e3, 10.0, 35.0, 10.0, 8.0), 0.05);
  // Fresh water loses the chemical relaxations: much less absorption at 100 kHz.
  EXPECT_LT(absorption_francois_garrison(100e3, 10.0, 0.0, 10.0, 8.0),
            0.2 * absorption_francois_garrison(100e3, 10.0, 35.0, 10.0, 8.0));
}

TEST(SonarModel, LoadsTheVehicleFileWithPresets) {
  const auto sonars = load_sonars(kRoot + "/config/sensors/bluerov2_sonars.yaml");
  ASSERT_EQ(sonars.size(), 3u);
  const SonarModel& fls = sonars[0];
  EXPECT_EQ(fls.name, "fls");
  EXPECT_FALSE(fls.side_scan());
  EXPECT_EQ(fls.beams, 256);                                    // overrides the preset's 512
  EXPECT_DOUBLE_EQ(fls.frequency_hz, 750e3);                    // from the preset
  EXPECT_NEAR(fls.horizontal_aperture_rad, 130 * kDeg, 1e-12);  // from the preset
  EXPECT_NEAR(fls.max_range_m, 20.0, 1e-12);
  EXPECT_NEAR(fls.bin_width_m(), (20.0 - 0.3) / 512, 1e-12);
  EXPECT_NEAR(fls.beam_azimuth_rad(0), -65 * kDeg + 0.5 * 130 * kDeg / 256, 1e-12);
  EXPECT_NEAR(fls.beam_azimuth_rad(255), 65 * kDeg - 0.5 * 130 * kDeg / 256, 1e-12);
  const SonarModel& prof = sonars[2];
  EXPECT_TRUE(prof.profiling());
  EXPECT_FALSE(prof.side_scan());
  EXPECT_EQ(prof.channels(), 256);
  EXPECT_NEAR(prof.vertical_aperture_rad, 3 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(prof.detection_db, 10.0);
  const SonarModel& ss = sonars[1];
  EXPECT_TRUE(ss.side_scan());
  EXPECT_EQ(ss.channels(), 2);
  EXPECT_NEAR(ss.tilt_rad, 20 * kDeg, 1e-12);
  EXPECT_EQ(ss.bins, 1024);
  EXPECT_EQ(load_sonar(kRoot + "/config/sensors/bluerov2_sonars.yaml", "sidescan").name, "sidescan");
  try {
    load_sonar(kRoot + "/config/sensors/bluerov2_sonars.yaml", "nope");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("fls, sidescan"), std::string::npos) << e.what();
  }
}

TEST(SonarModel, FramesOfHeadsAndMessages) {
  SonarModel ss = sonar_preset("sidescan_900k");
  const auto heads = ss.head_poses();
  ASSERT_EQ(heads.size(), 2u);
  // Port looks to -y (port) and down by the tilt; starboard to +y and down.
  const Eigen::Vector3d port = heads[0].linear().col(0), stbd = heads[1].linear().col(0);
  EXPECT_NEAR(port.y(), -std::cos(ss.tilt_rad), 1e-12);
  EXPECT_NEAR(port.z(), std::sin(ss.tilt_rad), 1e-12);
  EXPECT_NEAR(stbd.y(), std::cos(ss.tilt_rad), 1e-12);
  EXPECT_NEAR(stbd.z(), std::sin(ss.tilt_rad), 1e-12);
  // marine_acoustic_msgs frame: z = boresight, x = up, right-handed.
  SonarModel fls;
  const Eigen::Matrix3d R = fls.frame_acoustic().linear();
  EXPECT_TRUE(R.col(2).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(R.col(0).isApprox(Eigen::Vector3d(0, 0, -1)));
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  // The two-way travel time at 40 m allows 1500 / 80 = 18.75 pings/s.
  EXPECT_NEAR(fls.max_ping_rate_hz(1500.0), 18.75, 1e-12);
}

TEST(SonarModel, BadConfigNamesFileKeyValueAndRule) {
  auto has = [](const std::string& err, const std::string& what) { return err.find(what) != std::string::npos; };
  std::string e = load_error("    beams: 0\n");
  EXPECT_TRUE(has(e, "sonars[0].beams") && has(e, ">= 1")) << e;
  e = load_error("    min_range_m: 5\n    max_range_m: 5\n");
  EXPECT_TRUE(has(e, "sonars[0].max_range_m") && has(e, "> min_range_m")) << e;
  e = load_error("    horizontal_aperture_deg: 190\n");
  EXPECT_TRUE(has(e, "horizontal_aperture_deg") && has(e, "190") && has(e, "(0, 180]")) << e;
  e = load_error("    vertical_aperture_deg: 0\n");
  EXPECT_TRUE(has(e, "vertical_aperture_deg")) << e;
  e = load_error("    ping_rate_hz: 100\n    max_range_m: 40\n");
  EXPECT_TRUE(has(e, "ping_rate_hz") && has(e, "two-way travel time")) << e;
  e = load_error("    preset: oculus_m9000\n");
  EXPECT_TRUE(has(e, "preset") && has(e, "oculus_m750d_lf")) << e;
  e = load_error("    beamz: 3\n");
  EXPECT_TRUE(has(e, "beamz")) << e;
  e = load_error("    bins: .nan\n");
  EXPECT_TRUE(has(e, "bins")) << e;
  e = load_error("    type: side_scan\n    beams: 4\n");
  EXPECT_TRUE(has(e, "1 beam per side")) << e;
  e = load_error("    frequency_hz: .inf\n");
  EXPECT_TRUE(has(e, "frequency_hz")) << e;
  EXPECT_EQ(load_error("    beams: 64\n    bins: 128\n    max_range_m: 10\n"), "");
}

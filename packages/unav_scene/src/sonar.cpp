#include "unav_scene/sonar.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "unav_common/config.hpp"
#include "unav_common/frames.hpp"
#include "unav_scene/errors.hpp"

namespace unav::scene {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The sonar YAML's schema (layout: config/sensors/bluerov2_sonars.yaml). A `preset` fills the
// values of a real unit; keys written next to it override them.
struct SonarMountSpec {
  Eigen::Vector3d xyz_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();
  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("xyz_m", &xyz_m).Unit("m").Doc("position on base_link_frd"));
    a->Visit(Field("rpy_deg", &rpy_deg).Unit("deg").Doc("head (x = boresight) roll, pitch, yaw; pitch < 0 looks down"));
  }
};

struct SonarSpec {
  std::string name;
  std::string preset;
  std::string type = "forward_looking";
  SonarMountSpec mount;
  int beams = 256, bins = 512;
  double horizontal_aperture_deg = 130.0, vertical_aperture_deg = 20.0, tilt_deg = 0.0;
  double min_range_m = 0.1, max_range_m = 40.0;
  double frequency_hz = 750e3, ping_rate_hz = 10.0;
  double spreading_exponent = 2.0;
  bool tvg = true;
  double tvg_db_per_decade = 30.0;
  double gain_db = 0.0, dynamic_range_db = 60.0, speckle = 1.0, noise_floor_db = -45.0;
  bool sidelobes = false;
  double sidelobe_db = -30.0, sidelobe_falloff_db_per_octave = 6.0;
  double speckle_shape = 4.0, speckle_grain_beams = 1.7, speckle_grain_bins = 1.5;
  std::string display = "db";
  double display_gamma = 0.5;
  int vertical_samples = 0, beam_oversample = 2;
  std::string data_type = "uint8";
  double detection_db = 10.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using common::Field;
    a->Visit(Field("name", &name).Doc("sonar name (topics sonar/<name>/..., frame <name>_link); required"));
    a->Visit(Field("preset", &preset).Doc("a real unit's values (keys given here override them)"));
    a->Visit(Field("type", &type)
                 .OneOf({"forward_looking", "side_scan", "profiling"})
                 .Doc("imaging fan, two side-scan beams, or a profiling fan (a range per beam)"));
    a->Visit(Field("mount", &mount).Doc("head pose on base_link_frd (side-scan: the vehicle-fixed reference)"));
    a->Visit(Field("beams", &beams).Range(0, 4096).Doc("FLS beams across the fan (side-scan: 1)"));
    a->Visit(Field("bins", &bins).Range(0, 16384).Doc("range bins"));
    a->Visit(Field("horizontal_aperture_deg", &horizontal_aperture_deg)
                 .Unit("deg")
                 .Doc("FLS fan width; side-scan along-track beam width; (0, 180]"));
    a->Visit(Field("vertical_aperture_deg", &vertical_aperture_deg)
                 .Unit("deg")
                 .Doc("-3 dB vertical beam width; side-scan across-track; (0, 120]"));
    a->Visit(Field("tilt_deg", &tilt_deg).Range(0.0, 89.0).Unit("deg").Doc("side-scan beam depression"));
    a->Visit(Field("min_range_m", &min_range_m).Unit("m").Doc("first range bin's start, >= 0"));
    a->Visit(Field("max_range_m", &max_range_m).Unit("m").Doc("last range bin's end, > min_range_m"));
    a->Visit(Field("frequency_hz", &frequency_hz).Unit("Hz").Doc("centre frequency, 1 kHz..3 MHz"));
    a->Visit(Field("ping_rate_hz", &ping_rate_hz).Unit("Hz").Doc("<= c / (2 max_range_m)"));
    a->Visit(Field("spreading_exponent", &spreading_exponent).Range(1.0, 2.0).Doc("one-way TL = n 10 log10 r + a r"));
    a->Visit(Field("tvg", &tvg).Doc("time-varied gain: + tvg_db_per_decade log10 r + 2 alpha r"));
    a->Visit(Field("tvg_db_per_decade", &tvg_db_per_decade).Range(0.0, 60.0).Unit("dB").Doc("30: seabed, 40: points"));
    a->Visit(Field("gain_db", &gain_db).Range(-200.0, 200.0).Unit("dB").Doc("display gain"));
    a->Visit(Field("dynamic_range_db", &dynamic_range_db).Range(1.0, 200.0).Unit("dB").Doc("display dynamic range"));
    a->Visit(Field("speckle", &speckle).Range(0.0, 1.0).Doc("multiplicative speckle share (0 = none, 1 = developed)"));
    a->Visit(Field("speckle_shape", &speckle_shape)
                 .Range(0.0, 1000.0)
                 .Doc("K-distribution shape of the speckle (contrast sqrt(1 + 2 / shape)); 0 = Rayleigh"));
    a->Visit(Field("speckle_grain_beams", &speckle_grain_beams)
                 .Range(0.0, 64.0)
                 .Doc("speckle grain across beams: FWHM of its autocorrelation [beams]; <= 1 independent"));
    a->Visit(Field("speckle_grain_bins", &speckle_grain_bins)
                 .Range(0.0, 64.0)
                 .Doc("speckle grain along range (the pulse length) [bins]"));
    a->Visit(Field("noise_floor_db", &noise_floor_db).Range(-200.0, 0.0).Unit("dB").Doc("background re full scale"));
    a->Visit(
        Field("sidelobes", &sidelobes).Doc("FLS/profiling: beams hear the others' echoes through their side lobes"));
    a->Visit(Field("sidelobe_db", &sidelobe_db)
                 .Range(-200.0, -3.0)
                 .Unit("dB")
                 .Doc("first side lobe re the main lobe (uniform shading -13.3, Hann -31.5)"));
    a->Visit(Field("sidelobe_falloff_db_per_octave", &sidelobe_falloff_db_per_octave)
                 .Range(0.0, 60.0)
                 .Unit("dB")
                 .Doc("the side-lobe envelope's fall per doubling of the angle (uniform 6, Hann 18)"));
    a->Visit(Field("vertical_samples", &vertical_samples).Range(0, 4096).Doc("render rows; 0 = auto"));
    a->Visit(Field("beam_oversample", &beam_oversample).Range(1, 16).Doc("render columns per beam"));
    a->Visit(Field("data_type", &data_type).OneOf({"uint8", "float32"}).Doc("message samples"));
    a->Visit(
        Field("display", &display).OneOf({"db", "gamma"}).Doc("8-bit coding: dB (gain, range) or amplitude^gamma"));
    a->Visit(Field("display_gamma", &display_gamma).Range(0.05, 4.0).Doc("gamma coding's exponent on the amplitude"));
    a->Visit(Field("detection_db", &detection_db)
                 .Range(0.0, 100.0)
                 .Unit("dB")
                 .Doc("profiling: a beam's peak this far above its median level is a return"));
  }
};

struct SonarFile {
  std::string description;
  std::vector<SonarSpec> sonars;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(common::Field("description", &description));
    a->Visit(common::Field("sonars", &sonars).Doc("the sonars of the vehicle"));
  }
};

SonarSpec spec_of(const SonarModel& m) {
  SonarSpec s;
  s.name = m.name;
  s.type = m.type_name();
  s.detection_db = m.detection_db;
  s.beams = m.beams;
  s.bins = m.bins;
  s.horizontal_aperture_deg = m.horizontal_aperture_rad / kDeg;
  s.vertical_aperture_deg = m.vertical_aperture_rad / kDeg;
  s.tilt_deg = m.tilt_rad / kDeg;
  s.min_range_m = m.min_range_m;
  s.max_range_m = m.max_range_m;
  s.frequency_hz = m.frequency_hz;
  s.ping_rate_hz = m.ping_rate_hz;
  s.spreading_exponent = m.spreading_exponent;
  s.tvg = m.tvg;
  s.tvg_db_per_decade = m.tvg_db_per_decade;
  s.gain_db = m.gain_db;
  s.dynamic_range_db = m.dynamic_range_db;
  s.speckle = m.speckle;
  s.speckle_shape = m.speckle_shape;
  s.speckle_grain_beams = m.speckle_grain_beams;
  s.speckle_grain_bins = m.speckle_grain_bins;
  s.display = m.display;
  s.display_gamma = m.display_gamma;
  s.noise_floor_db = m.noise_floor_db;
  s.sidelobes = m.sidelobes;
  s.sidelobe_db = m.sidelobe_db;
  s.sidelobe_falloff_db_per_octave = m.sidelobe_falloff_db_per_octave;
  s.vertical_samples = m.vertical_samples;
  s.beam_oversample = m.beam_oversample;
  s.data_type = m.data_type;
  return s;
}

SonarModel model_of(const SonarSpec& s) {
  SonarModel m;
  m.name = s.name;
  m.type = s.type == "side_scan"   ? SonarModel::Type::kSideScan
           : s.type == "profiling" ? SonarModel::Type::kProfiling
                                   : SonarModel::Type::kForwardLooking;
  m.detection_db = s.detection_db;
  m.X_BH = common::pose_from_xyz_rpy(s.mount.xyz_m, s.mount.rpy_deg * kDeg);
  m.beams = s.beams;
  m.bins = s.bins;
  m.horizontal_aperture_rad = s.horizontal_aperture_deg * kDeg;
  m.vertical_aperture_rad = s.vertical_aperture_deg * kDeg;
  m.tilt_rad = s.tilt_deg * kDeg;
  m.min_range_m = s.min_range_m;
  m.max_range_m = s.max_range_m;
  m.frequency_hz = s.frequency_hz;
  m.ping_rate_hz = s.ping_rate_hz;
  m.spreading_exponent = s.spreading_exponent;
  m.tvg = s.tvg;
  m.tvg_db_per_decade = s.tvg_db_per_decade;
  m.gain_db = s.gain_db;
  m.dynamic_range_db = s.dynamic_range_db;
  m.speckle = s.speckle;
  m.speckle_shape = s.speckle_shape;
  m.speckle_grain_beams = s.speckle_grain_beams;
  m.speckle_grain_bins = s.speckle_grain_bins;
  m.display = s.display;
  m.display_gamma = s.display_gamma;
  m.noise_floor_db = s.noise_floor_db;
  m.sidelobes = s.sidelobes;
  m.sidelobe_db = s.sidelobe_db;
  m.sidelobe_falloff_db_per_octave = s.sidelobe_falloff_db_per_octave;
  m.vertical_samples = s.vertical_samples;
  m.beam_oversample = s.beam_oversample;
  m.data_type = s.data_type;
  return m;
}

}  // namespace

const char* SonarModel::type_name() const {
  switch (type) {
    case Type::kSideScan:
      return "side_scan";
    case Type::kProfiling:
      return "profiling";
    case Type::kForwardLooking:
      break;
  }
  return "forward_looking";
}

double SonarModel::beam_azimuth_rad(int k) const {
  const double step = horizontal_aperture_rad / beams;
  return -0.5 * horizontal_aperture_rad + (k + 0.5) * step;
}

std::vector<Pose> SonarModel::head_poses() const {
  if (!side_scan()) return {X_BH};
  std::vector<Pose> heads;
  for (const double side : {-1.0, 1.0}) {  // port (yaw -90 deg), starboard (+90 deg)
    const Pose X_HS = common::pose_from_xyz_rpy(Eigen::Vector3d::Zero(), {0.0, -tilt_rad, side * M_PI / 2});
    heads.push_back(X_BH * X_HS);
  }
  return heads;
}

Pose SonarModel::frame_acoustic() const {
  // Columns: the acoustic frame's axes in the head frame. x up = -z_H, y = y_H, z forward = x_H.
  Eigen::Matrix3d R_HA;
  R_HA << 0, 0, 1,  //
      0, 1, 0,      //
      -1, 0, 0;
  Pose X = X_BH;
  X.linear() = X_BH.linear() * R_HA;
  return X;
}

void SonarModel::validate(const std::string& where) const { check(where, name.empty() ? std::string("sonar") : name); }

void SonarModel::check(const std::string& file, const std::string& key) const {
  auto fail = [&](const std::string& k, const std::string& value, const std::string& rule) {
    throw ConfigError(file, key + "." + k, value, rule);
  };
  if (name.empty()) fail("name", "", "a sonar needs a name");
  if (beams < 1) fail("beams", std::to_string(beams), "must be >= 1");
  if (side_scan() && beams != 1) fail("beams", std::to_string(beams), "a side-scan sonar has 1 beam per side");
  if (bins < 2) fail("bins", std::to_string(bins), "must be >= 2");
  if (!(horizontal_aperture_rad > 0.0 && horizontal_aperture_rad <= M_PI + 1e-12))
    fail("horizontal_aperture_deg", num(horizontal_aperture_rad / kDeg), "must be in (0, 180] deg");
  if (!(vertical_aperture_rad > 0.0 && vertical_aperture_rad <= 120.0 * kDeg + 1e-12))
    fail("vertical_aperture_deg", num(vertical_aperture_rad / kDeg), "must be in (0, 120] deg");
  if (!(min_range_m >= 0.0)) fail("min_range_m", num(min_range_m), "must be >= 0");
  if (!(max_range_m > min_range_m))
    fail("max_range_m", num(max_range_m), "must be > min_range_m (" + num(min_range_m) + ")");
  if (!(frequency_hz >= 1e3 && frequency_hz <= 3e6))
    fail("frequency_hz", num(frequency_hz), "must be in [1 kHz, 3 MHz]");
  if (!(ping_rate_hz > 0.0)) fail("ping_rate_hz", num(ping_rate_hz), "must be > 0");
  // Sound speed is at most ~1560 m/s in the ocean: one ping must have returned from max range
  // before the next is sent (the exact limit with the water's sound speed: max_ping_rate_hz()).
  if (ping_rate_hz > max_ping_rate_hz(1560.0))
    fail("ping_rate_hz", num(ping_rate_hz),
         "must be <= c / (2 max_range_m) = " + num(max_ping_rate_hz(1560.0)) + " Hz (two-way travel time)");
  if (side_scan() && !(tilt_rad + 0.5 * vertical_aperture_rad < M_PI / 2))
    fail("tilt_deg", num(tilt_rad / kDeg), "tilt + vertical_aperture / 2 must stay below 90 deg");
  if (!(spreading_exponent >= 1.0 && spreading_exponent <= 2.0))
    fail("spreading_exponent", num(spreading_exponent), "must be in [1, 2]");
  if (!(tvg_db_per_decade >= 0.0 && tvg_db_per_decade <= 60.0))
    fail("tvg_db_per_decade", num(tvg_db_per_decade), "must be in [0, 60]");
  if (!(dynamic_range_db > 0.0)) fail("dynamic_range_db", num(dynamic_range_db), "must be > 0");
  if (!(speckle >= 0.0 && speckle <= 1.0)) fail("speckle", num(speckle), "must be in [0, 1]");
  if (!std::isfinite(gain_db)) fail("gain_db", num(gain_db), "must be finite");
  if (!(noise_floor_db <= 0.0)) fail("noise_floor_db", num(noise_floor_db), "must be <= 0 dB re full scale");
  if (!(sidelobe_db >= -200.0 && sidelobe_db <= -3.0))
    fail("sidelobe_db", num(sidelobe_db), "must be in [-200, -3] dB re the main lobe");
  if (!(sidelobe_falloff_db_per_octave >= 0.0 && sidelobe_falloff_db_per_octave <= 60.0))
    fail("sidelobe_falloff_db_per_octave", num(sidelobe_falloff_db_per_octave), "must be in [0, 60] dB");
  if (beam_oversample < 1) fail("beam_oversample", std::to_string(beam_oversample), "must be >= 1");
  if (vertical_samples < 0) fail("vertical_samples", std::to_string(vertical_samples), "must be >= 0");
  if (data_type != "uint8" && data_type != "float32") fail("data_type", data_type, "must be uint8 or float32");
  if (!X_BH.matrix().allFinite()) fail("mount", "", "pose must be finite");
}

std::vector<std::string> sonar_preset_names() {
  return {"oculus_m750d_lf", "oculus_m750d_hf", "oculus_m1200d_lf", "oculus_m1200d_hf", "sidescan_900k"};
}

SonarModel sonar_preset(const std::string& name) {
  // Blueprint Subsea Oculus M-series datasheets: 512 beams; M750d 750 kHz (130 x 20 deg, to
  // 120 m) / 1.2 MHz (70 x 12 deg, to 40 m); M1200d 1.2 MHz (130 x 20 deg, to 30 m) / 2.1 MHz
  // (60 x 12 deg, to 10 m). Ranges here are typical inspection settings, not the unit maxima.
  SonarModel m;
  m.beams = 512;
  m.gain_db = 6.0;  // sand at 2-3 m altitude in mid-grey with the 30 dB/decade TVG
  if (name == "oculus_m750d_lf") {
    m.frequency_hz = 750e3, m.horizontal_aperture_rad = 130 * kDeg, m.vertical_aperture_rad = 20 * kDeg;
    m.max_range_m = 30.0;
  } else if (name == "oculus_m750d_hf") {
    m.frequency_hz = 1.2e6, m.horizontal_aperture_rad = 70 * kDeg, m.vertical_aperture_rad = 12 * kDeg;
    m.max_range_m = 20.0;
  } else if (name == "oculus_m1200d_lf") {
    m.frequency_hz = 1.2e6, m.horizontal_aperture_rad = 130 * kDeg, m.vertical_aperture_rad = 20 * kDeg;
    m.max_range_m = 20.0;
  } else if (name == "oculus_m1200d_hf") {
    m.frequency_hz = 2.1e6, m.horizontal_aperture_rad = 60 * kDeg, m.vertical_aperture_rad = 12 * kDeg;
    m.max_range_m = 10.0;
  } else if (name == "sidescan_900k") {
    // A generic 900 kHz side-scan of the size an ROV carries: 0.3 deg along track (rendered as
    // a 1 deg strip), 50 deg across track, beams depressed 20 deg, 30 m a side.
    m.type = SonarModel::Type::kSideScan;
    m.beams = 1;
    m.bins = 1024;
    m.frequency_hz = 900e3, m.horizontal_aperture_rad = 1.0 * kDeg, m.vertical_aperture_rad = 50 * kDeg;
    m.tilt_rad = 20 * kDeg;
    m.min_range_m = 0.5, m.max_range_m = 30.0;
    m.ping_rate_hz = 20.0;
  } else {
    std::string list;
    for (const auto& n : sonar_preset_names()) list += (list.empty() ? "" : ", ") + n;
    throw ConfigError("unknown sonar preset '" + name + "' (valid: " + list + ")");
  }
  return m;
}

std::vector<SonarModel> load_sonars(const std::string& path) {
  // Pass 1: every key, type and per-field rule, with errors naming sonars[i].key.
  const auto file = common::LoadYamlFile<SonarFile>(path);
  if (file.sonars.empty()) throw ConfigError(path, "sonars", "", "expected a non-empty list of sonars");
  const YAML::Node root = common::detail::ReadYamlFile(path);
  std::vector<SonarModel> out;
  for (std::size_t i = 0; i < file.sonars.size(); ++i) {
    const std::string key = "sonars[" + std::to_string(i) + "]";
    SonarSpec spec = file.sonars[i];
    if (spec.name.empty()) throw ConfigError(path, key + ".name", "", "a sonar needs a name");
    // Pass 2: a preset's values, then the keys written in the file over them.
    if (!spec.preset.empty()) {
      try {
        SonarSpec merged = spec_of(sonar_preset(spec.preset));
        const YAML::Node n = root["sonars"][i];
        for (const auto& kv : n) {
          std::ostringstream text;
          text << YAML::Dump(kv.second);
          common::ApplyOverride(&merged, kv.first.as<std::string>(), text.str(), path);
        }
        spec = merged;
      } catch (const ConfigError& e) {
        throw ConfigError(path, key + ".preset", spec.preset, e.what());
      }
    }
    SonarModel m = model_of(spec);
    m.check(path, key);
    for (const auto& o : out)
      if (o.name == m.name) throw ConfigError(path, key + ".name", m.name, "duplicate sonar name");
    out.push_back(m);
  }
  return out;
}

SonarModel load_sonar(const std::string& path, const std::string& name) {
  std::string names;
  for (const auto& s : load_sonars(path)) {
    if (s.name == name) return s;
    names += (names.empty() ? "" : ", ") + s.name;
  }
  throw ConfigError(path, "sonars", name, "no sonar of that name (sonars: " + names + ")");
}

double sound_speed_mackenzie(double T, double S, double D) {
  return 1448.96 + 4.591 * T - 5.304e-2 * T * T + 2.374e-4 * T * T * T + 1.340 * (S - 35.0) + 1.630e-2 * D +
         1.675e-7 * D * D - 1.025e-2 * T * (S - 35.0) - 7.139e-13 * T * D * D * D;
}

double absorption_francois_garrison(double frequency_hz, double T, double S, double D, double pH) {
  const double f = frequency_hz / 1000.0;  // kHz
  const double c = 1412.0 + 3.21 * T + 1.19 * S + 0.0167 * D;
  const double theta = 273.0 + T;
  // Boric acid.
  const double A1 = 8.86 / c * std::pow(10.0, 0.78 * pH - 5.0);
  const double f1 = 2.8 * std::sqrt(S / 35.0) * std::pow(10.0, 4.0 - 1245.0 / theta);
  // Magnesium sulphate.
  const double A2 = 21.44 * S / c * (1.0 + 0.025 * T);
  const double P2 = 1.0 - 1.37e-4 * D + 6.2e-9 * D * D;
  const double f2 = 8.17 * std::pow(10.0, 8.0 - 1990.0 / theta) / (1.0 + 0.0018 * (S - 35.0));
  // Pure water.
  const double A3 = T <= 20.0 ? 4.937e-4 - 2.59e-5 * T + 9.11e-7 * T * T - 1.50e-8 * T * T * T
                              : 3.964e-4 - 1.146e-5 * T + 1.45e-7 * T * T - 6.5e-10 * T * T * T;
  const double P3 = 1.0 - 3.83e-5 * D + 4.9e-10 * D * D;
  const double f2sq = f * f;
  const double db_per_km = A1 * f1 * f2sq / (f1 * f1 + f2sq) + A2 * P2 * f2 * f2sq / (f2 * f2 + f2sq) + A3 * P3 * f2sq;
  return db_per_km / 1000.0;
}

double absorption_ainslie_mccolm(double frequency_hz, double T, double S, double D, double pH) {
  const double f = frequency_hz / 1000.0, z = D / 1000.0;  // kHz, km
  const double f1 = 0.78 * std::sqrt(S / 35.0) * std::exp(T / 26.0);
  const double f2 = 42.0 * std::exp(T / 17.0);
  const double ff = f * f;
  const double db_per_km = 0.106 * f1 * ff / (f1 * f1 + ff) * std::exp((pH - 8.0) / 0.56) +
                           0.52 * (1.0 + T / 43.0) * (S / 35.0) * f2 * ff / (f2 * f2 + ff) * std::exp(-z / 6.0) +
                           0.00049 * ff * std::exp(-(T / 27.0 + z / 17.0));
  return db_per_km / 1000.0;
}

Acoustics water_acoustics(const WaterModel& water, double depth_m, double frequency_hz) {
  const double d = std::max(0.0, depth_m);
  Acoustics a;
  a.sound_speed_mps = sound_speed_mackenzie(water.temperature_c, water.salinity_psu, d);
  a.absorption_db_per_m =
      absorption_francois_garrison(frequency_hz, water.temperature_c, water.salinity_psu, d, water.ph);
  return a;
}

}  // namespace unav::scene

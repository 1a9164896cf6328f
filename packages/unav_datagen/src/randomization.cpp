#include "unav_datagen/randomization.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <utility>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_common/sampling.hpp"
#include "unav_datagen/dataset_writer.hpp"
#include "unav_scene/water.hpp"

namespace fs = std::filesystem;

namespace unav::datagen {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One key of the language with its rule. Reals and ints have a range (open or closed ends);
// strings a set of allowed values (empty = any).
struct KeyRule {
  const char* path;
  const char* type;  // real, int, string, path
  double lo, hi;
  bool lo_open, hi_open;
  std::vector<std::string> allowed;
  const char* fallback;
  const char* doc;
  bool randomizable;
  const char* per_item;  // key whose value gives how many draws ("" = one)
};

const std::vector<KeyRule>& rules() {
  static const std::vector<KeyRule> r = [] {
    std::vector<std::string> presets = unav::scene::jerlov_preset_names();
    std::vector<KeyRule> v = {
        {"seed", "int", 0, 9007199254740992.0, false, false, {}, "0", "base seed: sample k uses seed + k", false, ""},
        {"base_world",
         "path",
         0,
         0,
         false,
         false,
         {},
         "worlds/pipe_inspection/world.yaml",
         "world the samples start from (seabed size, materials, marine snow particles); relative to the spec's "
         "folder or the resource roots",
         false,
         ""},
        {"cameras_config",
         "path",
         0,
         0,
         false,
         false,
         {},
         "config/sensors/bluerov2_cameras.yaml",
         "camera set (mounts, intrinsics)",
         false,
         ""},
        {"sonars_config",
         "path",
         0,
         0,
         false,
         false,
         {},
         "config/sensors/bluerov2_sonars.yaml",
         "sonar set (mounts, presets) for output.sonar",
         false,
         ""},
        {"output.format", "string", 0, 0, false, false, {"tum", "euroc", "kitti"}, "tum", "dataset layout", false, ""},
        {"output.camera", "string", 0, 0, false, false, {}, "down", "camera of cameras_config to render", false, ""},
        {"output.width", "int", 16, 4096, false, false, {}, "640", "image width [px] (intrinsics scaled)", false, ""},
        {"output.height", "int", 16, 4096, false, false, {}, "480", "image height [px]", false, ""},
        {"output.frames", "int", 1, 1000000, false, false, {}, "100", "frames per sample", false, ""},
        {"output.rate_hz", "real", 0, 100, true, false, {}, "10", "camera frame rate [Hz]", false, ""},
        {"output.sonar",
         "string",
         0,
         0,
         false,
         false,
         {},
         "",
         "sonar of sonars_config to ping at its rate along the flight (\"\" = none): sonar/<name>/ pings + geometry "
         "in the manifest",
         false,
         ""},
        {"water.preset", "string", 0, 0, false, false, presets, "jerlov_IB", "Jerlov water type", true, ""},
        {"water.turbidity",
         "real",
         0,
         10,
         true,
         false,
         {},
         "1.0",
         "factor on the preset's attenuation, backscatter, diffuse and scattering coefficients",
         true,
         ""},
        {"water.marine_snow_per_m3",
         "real",
         0,
         2000,
         false,
         false,
         {},
         "25",
         "marine snow particles per m^3",
         true,
         ""},
        {"seabed.depth_m", "real", 1, 1000, false, false, {}, "10", "seabed depth below the surface [m]", true, ""},
        {"seabed.texture",
         "string",
         0,
         0,
         false,
         false,
         {"sand", "rock", "checker", "none"},
         "sand",
         "procedural seabed texture",
         true,
         ""},
        {"seabed.relief_m", "real", 0, 2, false, false, {}, "0.15", "amplitude of the seabed relief [m]", true, ""},
        {"seabed.relief_wavelength_m",
         "real",
         0.5,
         100,
         false,
         false,
         {},
         "5",
         "wavelength of the relief [m]",
         true,
         ""},
        {"sun.elevation_deg", "real", 1, 90, false, false, {}, "70", "sun elevation above the horizon [deg]", true, ""},
        {"sun.azimuth_deg", "real", -360, 360, false, false, {}, "30", "sun azimuth from north [deg]", true, ""},
        {"sun.irradiance", "real", 0, 10, false, false, {}, "1.0", "surface irradiance (white, linear)", true, ""},
        {"lamps.count", "int", 0, 8, false, false, {}, "2", "vehicle lamps (spread across the bow)", true, ""},
        {"lamps.intensity", "real", 0, 50, false, false, {}, "3.0", "lamp intensity (linear)", true, ""},
        {"lamps.half_angle_deg", "real", 1, 89, false, false, {}, "45", "lamp cone half angle [deg]", true, ""},
        {"pipeline.segments", "int", 1, 8, false, false, {}, "3", "straight runs of the pipeline", true, ""},
        {"pipeline.segment_length_m",
         "real",
         1,
         100,
         false,
         false,
         {},
         "7",
         "length of each run [m] (drawn per run)",
         true,
         "pipeline.segments"},
        {"pipeline.turn_deg",
         "real",
         -120,
         120,
         false,
         false,
         {},
         "45",
         "heading change between runs [deg] (drawn per run; the first run heads north)",
         true,
         "pipeline.segments"},
        {"pipeline.radius_m", "real", 0.05, 2, false, false, {}, "0.25", "pipe radius [m]", true, ""},
        {"pipeline.burial_fraction",
         "real",
         0,
         0.95,
         false,
         false,
         {},
         "0.2",
         "share of the diameter below the seabed",
         true,
         ""},
        {"pipeline.growth",
         "real",
         0,
         1,
         false,
         false,
         {},
         "0",
         "marine growth on the coating: 0 clean, 1 fully overgrown (albedo to green-brown)",
         true,
         ""},
        {"rocks.count", "int", 0, 2000, false, false, {}, "45", "rocks scattered around the pipeline", true, ""},
        {"rocks.max_radius_m",
         "real",
         0.1,
         3,
         false,
         false,
         {},
         "0.45",
         "largest rock radius [m] (smallest 0.08)",
         true,
         ""},
        {"objects.folder",
         "path",
         0,
         0,
         false,
         false,
         {},
         "",
         "folder of mesh files (obj, ply, stl, gltf, glb, fbx, dae) placed by assimp; empty = none",
         false,
         ""},
        {"objects.count",
         "int",
         0,
         100,
         false,
         false,
         {},
         "0",
         "meshes from objects.folder placed near the pipe",
         true,
         ""},
        {"objects.scale", "real", 0.01, 100, false, false, {}, "1.0", "scale of the placed meshes", true, ""},
        {"current.speed_mps", "real", 0, 3, false, false, {}, "0", "constant water current speed [m/s]", true, ""},
        {"current.direction_deg",
         "real",
         -360,
         360,
         false,
         false,
         {},
         "0",
         "direction the current flows to [deg]",
         true,
         ""},
        {"camera.noise_stddev",
         "real",
         0,
         0.5,
         false,
         false,
         {},
         "0.01",
         "read noise, fraction of full scale (scaled by gain)",
         true,
         ""},
        {"camera.exposure", "real", 0, 20, true, false, {}, "1.0", "exposure (linear)", true, ""},
        {"camera.gain",
         "real",
         0,
         64,
         true,
         false,
         {},
         "1.0",
         "sensor gain: multiplies the signal and the read noise",
         true,
         ""},
        {"trajectory.kind",
         "string",
         0,
         0,
         false,
         false,
         {"follow_pipe", "lawnmower", "random_waypoints"},
         "follow_pipe",
         "what the vehicle flies",
         true,
         ""},
        {"trajectory.altitude_m", "real", 0.3, 50, false, false, {}, "1.5", "height above the seabed [m]", true, ""},
        {"trajectory.speed_mps", "real", 0, 3, true, false, {}, "0.3", "speed along the path [m/s]", true, ""},
        {"trajectory.lateral_offset_m",
         "real",
         -10,
         10,
         false,
         false,
         {},
         "0",
         "follow_pipe: offset to the right of the pipe [m]",
         true,
         ""},
        {"trajectory.lane_spacing_m",
         "real",
         0.5,
         50,
         false,
         false,
         {},
         "3",
         "lawnmower: distance between lanes [m]",
         true,
         ""},
        {"trajectory.waypoints", "int", 2, 100, false, false, {}, "6", "random_waypoints: how many", true, ""},
    };
    // Renderer switches (on by default): A/B comparisons of the realism over many scenes, or
    // domain randomisation ({choice: [true, false]}).
    const std::pair<const char*, const char*> switches[] = {
        {"render.shadows", "shadow maps of the sun and of every lamp"},
        {"render.caustics", "animated sunlight caustics on the seabed"},
        {"render.materials", "relief (bump mapping), GGX highlights and sediment cover of the materials"},
    };
    for (const auto& [path, doc] : switches)
      v.push_back({path, "string", 0, 0, false, false, {"true", "false"}, "true", doc, true, ""});
    return v;
  }();
  return r;
}

std::string rule_text(const KeyRule& k) {
  if (!k.allowed.empty()) {
    std::string s = "one of:";
    for (const auto& a : k.allowed) s += " " + a;
    return s;
  }
  if (std::string(k.type) == "real" || std::string(k.type) == "int") {
    std::ostringstream o;
    o << "in " << (k.lo_open ? "(" : "[") << k.lo << ", " << k.hi << (k.hi_open ? ")" : "]");
    return o.str();
  }
  return std::string(k.type) == "path" ? "an existing path" : "any string";
}

std::string node_text(const YAML::Node& n) {
  if (!n) return "";
  if (n.IsScalar()) return n.Scalar();
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

// The per-key generator: the workspace's SplitMix64, seeded from (sample seed, key path).
using Rng = unav::common::SplitMix64;
using unav::common::KeySeed;

class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& key, const YAML::Node& value, const std::string& rule) const {
    throw unav::ConfigError(file_, key, node_text(value), rule);
  }
  double number(const std::string& key, const YAML::Node& n) const {
    double v = 0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) fail(key, n, "expected a number");
    if (!std::isfinite(v)) fail(key, n, "must be finite");
    return v;
  }
  void check_value(const KeyRule& k, const std::string& key, const YAML::Node& n) const {
    const std::string type = k.type;
    if (type == "real" || type == "int") {
      const double v = number(key, n);
      if (type == "int" && v != std::floor(v)) fail(key, n, "expected an integer");
      const bool ok = (k.lo_open ? v > k.lo : v >= k.lo) && (k.hi_open ? v < k.hi : v <= k.hi);
      if (!ok) fail(key, n, "must be " + rule_text(k));
    } else {
      if (!n.IsScalar()) fail(key, n, "expected a string");
      if (!k.allowed.empty() && std::find(k.allowed.begin(), k.allowed.end(), n.Scalar()) == k.allowed.end())
        fail(key, n, "must be " + rule_text(k));
    }
  }
  // A fixed value or a distribution whose whole support obeys the key's rule.
  void check_leaf(const KeyRule& k, const std::string& key, const YAML::Node& n) const {
    if (!n.IsMap()) {
      check_value(k, key, n);
      return;
    }
    if (!k.randomizable) fail(key, n, "takes a fixed value, not a distribution");
    if (n.size() != 1)
      fail(key, n,
           "a distribution is one of {uniform: [lo, hi]}, {normal: {mean, std}}, {int: [lo, hi]}, {choice: [...]}");
    const std::string kind = n.begin()->first.Scalar();
    const YAML::Node a = n.begin()->second;
    const std::string type = k.type;
    const std::string dkey = key + "." + kind;
    if (kind == "uniform" || kind == "int") {
      if (type != "real" && type != "int") fail(dkey, a, "a " + type + " key takes a fixed value or {choice: [...]}");
      if (kind == "uniform" && type == "int") fail(dkey, a, "an int key takes {int: [lo, hi]} or {choice: [...]}");
      if (!a.IsSequence() || a.size() != 2) fail(dkey, a, "expected [lo, hi]");
      check_value(k, dkey, a[0]);
      check_value(k, dkey, a[1]);
      if (number(dkey, a[0]) > number(dkey, a[1])) fail(dkey, a, "empty range: lo > hi");
      if (kind == "int" && (number(dkey, a[0]) != std::floor(number(dkey, a[0])) ||
                            number(dkey, a[1]) != std::floor(number(dkey, a[1]))))
        fail(dkey, a, "expected integer ends");
    } else if (kind == "normal") {
      if (type != "real") fail(dkey, a, "only real keys take {normal: ...}");
      if (!a.IsMap()) fail(dkey, a, "expected {mean: m, std: s}");
      for (const auto& kv : a)
        if (kv.first.Scalar() != "mean" && kv.first.Scalar() != "std")
          fail(dkey + "." + kv.first.Scalar(), kv.second, "unknown key (known: mean, std)");
      if (!a["mean"] || !a["std"]) fail(dkey, a, "needs mean and std");
      check_value(k, dkey + ".mean", a["mean"]);
      if (!(number(dkey + ".std", a["std"]) >= 0.0)) fail(dkey + ".std", a["std"], "must be >= 0");
    } else if (kind == "choice") {
      if (!a.IsSequence() || a.size() == 0) fail(dkey, a, "expected a non-empty list");
      for (size_t i = 0; i < a.size(); ++i) check_value(k, dkey + "[" + std::to_string(i) + "]", a[i]);
    } else {
      fail(key, n, "unknown distribution '" + kind + "' (uniform, normal, int, choice)");
    }
  }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

// The node at "section.key" (or "key"), or an undefined node; never a yaml-cpp "zombie" node
// (which throws on use).
YAML::Node child(const YAML::Node& map, const std::string& key) {
  if (map && map.IsMap())
    for (const auto& kv : map)
      if (kv.first.Scalar() == key) return kv.second;
  return YAML::Node(YAML::NodeType::Undefined);
}

YAML::Node lookup(const YAML::Node& root, const std::string& path) {
  const size_t dot = path.find('.');
  if (dot == std::string::npos) return child(root, path);
  return child(child(root, path.substr(0, dot)), path.substr(dot + 1));
}

YAML::Node draw(const KeyRule& k, const YAML::Node& leaf, Rng& rng) {
  if (!leaf.IsMap()) return YAML::Clone(leaf);
  return unav::common::DrawDistribution(leaf, &rng, k.lo, k.hi);  // normal draws clipped to the key's range
}

std::string resolve_path(const std::string& value, const std::string& spec_dir) {
  if (value.empty()) return value;
  if (fs::path(value).is_absolute()) return value;
  const fs::path local = fs::path(spec_dir) / value;
  if (fs::exists(local)) return fs::absolute(local).lexically_normal().string();
  if (auto r = unav::common::try_find_resource(value)) return fs::absolute(*r).lexically_normal().string();
  // config/ prefix as the episode files use it ("sensors/x.yaml" under config/)
  if (auto r = unav::common::try_find_resource("config/" + value)) return fs::absolute(*r).lexically_normal().string();
  return "";
}

}  // namespace

const std::vector<SpecKey>& RandomizationSpec::keys() {
  static const std::vector<SpecKey> k = [] {
    std::vector<SpecKey> out;
    for (const auto& r : rules()) out.push_back({r.path, r.type, rule_text(r), r.fallback, r.doc, r.randomizable});
    return out;
  }();
  return k;
}

std::string RandomizationSpec::documentation() {
  std::ostringstream o;
  std::string section;
  for (const auto& k : keys()) {
    const std::string s = k.path.find('.') == std::string::npos ? "(top level)" : k.path.substr(0, k.path.find('.'));
    if (s != section) {
      section = s;
      o << "\n### " << s << "\n\n| key | type | rule | default | randomizable | meaning |\n|---|---|---|---|---|---|\n";
    }
    o << "| `" << k.path << "` | " << k.type << " | " << k.rule << " | `" << (k.fallback.empty() ? "\"\"" : k.fallback)
      << "` | " << (k.randomizable ? "yes" : "no") << " | " << k.doc << " |\n";
  }
  return o.str();
}

RandomizationSpec RandomizationSpec::load(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw unav::ConfigError(path, "", "", "cannot read the spec file");
  } catch (const YAML::ParserException& e) {
    throw unav::ConfigError(path, "", "", "malformed YAML at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  return parse(root, path);
}

RandomizationSpec RandomizationSpec::parse(const YAML::Node& root, const std::string& file) {
  const Checker c(file);
  if (!root || !root.IsMap()) throw unav::ConfigError(file, "", "", "a spec is a YAML map");
  // Unknown sections and keys first: a typo must not silently fall back to a default.
  std::set<std::string> sections, top;
  for (const auto& r : rules()) {
    const std::string p = r.path;
    if (p.find('.') == std::string::npos)
      top.insert(p);
    else
      sections.insert(p.substr(0, p.find('.')));
  }
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (key == "description" || key == "slurm") continue;
    if (top.count(key)) continue;
    if (!sections.count(key)) {
      std::string known;
      for (const auto& s : top) known += " " + s;
      for (const auto& s : sections) known += " " + s;
      c.fail(key, YAML::Node(), "unknown key (known:" + known + ", description, slurm)");
    }
    if (!kv.second.IsMap()) c.fail(key, kv.second, "expected a map of keys");
    for (const auto& sub : kv.second) {
      const std::string full = key + "." + sub.first.Scalar();
      const bool known = std::any_of(rules().begin(), rules().end(), [&](const KeyRule& r) { return full == r.path; });
      if (!known) {
        std::string list;
        for (const auto& r : rules())
          if (std::string(r.path).rfind(key + ".", 0) == 0) list += " " + std::string(r.path).substr(key.size() + 1);
        c.fail(full, sub.second, "unknown key (known in " + key + ":" + list + ")");
      }
    }
  }
  RandomizationSpec s;
  s.file_ = file;
  s.root_ = YAML::Clone(root);
  const std::string dir = fs::path(file).parent_path().string();
  for (const auto& r : rules()) {
    YAML::Node n = lookup(root, r.path);
    if (!n.IsDefined() || n.IsNull()) n.reset(YAML::Node(std::string(r.fallback)));
    if (std::string(r.type) == "path") {
      if (!n.IsScalar()) c.fail(r.path, n, "expected a path");
      if (!n.Scalar().empty()) {
        const std::string p = resolve_path(n.Scalar(), dir);
        if (p.empty())
          c.fail(r.path, n,
                 "no such file or folder (relative to " + (dir.empty() ? "." : dir) + " or the resource roots)");
        n.reset(YAML::Node(p));
      }
    } else {
      c.check_leaf(r, r.path, n);
    }
    s.leaves_.push_back(n);
  }
  // Validated above as an integer in [0, 2^53] (so exact as a double). Not as<uint64_t>: yaml-cpp
  // reads a leading 0 as octal and throws on "0999" (YAML 1.2: decimal 999).
  s.base_seed_ = static_cast<std::uint64_t>(s.leaves_[0].as<double>());
  s.base_world_ = s.leaves_[1].Scalar();
  s.cameras_config_ = s.leaves_[2].Scalar();
  for (size_t i = 0; i < rules().size(); ++i) {
    if (std::string(rules()[i].path) == "objects.folder") s.objects_folder_ = s.leaves_[i].Scalar();
    if (std::string(rules()[i].path) == "sonars_config") s.sonars_config_ = s.leaves_[i].Scalar();
  }
  if (!s.objects_folder_.empty()) {
    if (!fs::is_directory(s.objects_folder_))
      c.fail("objects.folder", YAML::Node(s.objects_folder_), "must be a folder");
    static const std::set<std::string> exts = {".obj", ".ply", ".stl", ".gltf", ".glb", ".fbx", ".dae"};
    for (const auto& e : fs::directory_iterator(s.objects_folder_)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (exts.count(ext)) s.object_meshes_.push_back(e.path().string());
    }
    std::sort(s.object_meshes_.begin(), s.object_meshes_.end());
    if (s.object_meshes_.empty())
      c.fail("objects.folder", YAML::Node(s.objects_folder_),
             "holds no mesh file (obj, ply, stl, gltf, glb, fbx, dae)");
  }
  // Cross-key rules, checked on the support of each distribution.
  const YAML::Node count = lookup(root, "objects.count");
  if (count && !count.IsNull() && s.objects_folder_.empty() && !(count.IsScalar() && count.as<double>(0) == 0))
    c.fail("objects.count", count, "needs objects.folder");
  return s;
}

YAML::Node RandomizationSpec::sample_seed(std::uint64_t seed) const {
  YAML::Node out;
  out["seed"] = seed;
  std::map<std::string, int64_t> drawn_ints;
  for (size_t i = 1; i < rules().size(); ++i) {
    const KeyRule& k = rules()[i];
    const std::string path = k.path;
    Rng rng{KeySeed(seed, path)};
    YAML::Node value;
    if (*k.per_item) {
      const int64_t n = drawn_ints.at(k.per_item);
      value = YAML::Node(YAML::NodeType::Sequence);
      for (int64_t j = 0; j < n; ++j) value.push_back(draw(k, leaves_[i], rng));
    } else {
      value = draw(k, leaves_[i], rng);
    }
    if (std::string(k.type) == "int") {
      const auto v = static_cast<int64_t>(std::llround(value.as<double>()));
      drawn_ints[path] = v;
      value = YAML::Node(v);
    }
    const size_t dot = path.find('.');
    if (dot == std::string::npos)
      out[path] = value;
    else
      out[path.substr(0, dot)][path.substr(dot + 1)] = value;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------

namespace {

YAML::Node vec3(double a, double b, double c) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.SetStyle(YAML::EmitterStyle::Flow);
  n.push_back(a);
  n.push_back(b);
  n.push_back(c);
  return n;
}

YAML::Node vec2(double a, double b) {
  YAML::Node n(YAML::NodeType::Sequence);
  n.SetStyle(YAML::EmitterStyle::Flow);
  n.push_back(a);
  n.push_back(b);
  return n;
}

void write_yaml(const std::string& path, const YAML::Node& n, const std::string& header) {
  std::ofstream f(path);
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << n;
  f << header << e.c_str() << "\n";
  f.flush();
  if (!f) throw DatasetError(path + ": cannot write");
}

}  // namespace

SampleWorld write_sample_world(const RandomizationSpec& spec, const YAML::Node& s, const std::string& dir) {
  YAML::Node w;
  try {
    w = YAML::LoadFile(spec.base_world());
  } catch (const YAML::Exception& e) {
    throw unav::ConfigError(spec.base_world(), "", "", std::string("cannot read the base world: ") + e.what());
  }
  const auto seed = s["seed"].as<std::uint64_t>();
  SampleWorld out;
  fs::create_directories(dir);
  w["name"] = w["name"].as<std::string>("world") + "_sample_" + std::to_string(seed);
  // File names only: the same seed gives the same bytes wherever the workspace or spec lives.
  w["description"] = "Randomized from " + fs::path(spec.base_world()).filename().string() + " by " +
                     fs::path(spec.file()).filename().string() + ", seed " + std::to_string(seed);

  // Water: the preset's coefficients scaled by the turbidity.
  const auto preset = unav::scene::jerlov_preset(s["water"]["preset"].as<std::string>());
  const double turb = s["water"]["turbidity"].as<double>();
  YAML::Node water;
  water["preset"] = s["water"]["preset"].as<std::string>();
  water["beta_D"] = vec3(turb * preset.beta_D.x(), turb * preset.beta_D.y(), turb * preset.beta_D.z());
  water["beta_B"] = vec3(turb * preset.beta_B.x(), turb * preset.beta_B.y(), turb * preset.beta_B.z());
  water["K_d"] = vec3(turb * preset.K_d.x(), turb * preset.K_d.y(), turb * preset.K_d.z());
  water["b_scatter"] = vec3(turb * preset.b_scatter.x(), turb * preset.b_scatter.y(), turb * preset.b_scatter.z());
  YAML::Node snow = w["water"] && w["water"]["marine_snow"] ? YAML::Clone(w["water"]["marine_snow"]) : YAML::Node();
  snow["density_per_m3"] = s["water"]["marine_snow_per_m3"].as<double>();
  snow["seed"] = static_cast<std::uint32_t>(seed % 1000003);
  water["marine_snow"] = snow;
  w["water"] = water;

  // Pipeline: runs from (0, 0) heading north, turning between runs.
  std::vector<Eigen::Vector2d> pts{{0.0, 0.0}};
  double heading = 0.0;
  const YAML::Node lengths = s["pipeline"]["segment_length_m"], turns = s["pipeline"]["turn_deg"];
  for (size_t i = 0; i < lengths.size(); ++i) {
    if (i > 0) heading += turns[i].as<double>() * M_PI / 180.0;
    const double L = lengths[i].as<double>();
    pts.push_back(pts.back() + L * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
  }
  Eigen::Vector2d lo = pts[0], hi = pts[0];
  for (const auto& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double radius = s["pipeline"]["radius_m"].as<double>();
  const double g = s["pipeline"]["growth"].as<double>();
  YAML::Node pipe;
  pipe["name"] = "main";
  pipe["radius_m"] = radius;
  pipe["bend_radius_m"] = std::max(1.5, 4.0 * radius);
  pipe["burial_fraction"] = s["pipeline"]["burial_fraction"].as<double>();
  YAML::Node pn(YAML::NodeType::Sequence);
  for (const auto& p : pts) pn.push_back(vec2(p.x(), p.y()));
  pipe["points_ne"] = pn;
  pipe["material"]["texture"] = "pipe_coating";
  pipe["material"]["albedo"] = vec3(1.0 - 0.65 * g, 1.0 - 0.55 * g, 1.0 - 0.75 * g);
  pipe["material"]["uv_scale_m"] = 3.0;
  w["pipelines"] = YAML::Node(YAML::NodeType::Sequence);
  w["pipelines"].push_back(pipe);

  // Seabed: centred on the pipeline, 12 m of margin, a whole number of cells.
  YAML::Node sb = w["seabed"] ? YAML::Clone(w["seabed"]) : YAML::Node();
  const double res = sb["resolution_m"].as<double>(1.0);
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const double side = std::ceil(((hi - lo).maxCoeff() + 24.0) / res) * res;
  sb["depth_m"] = s["seabed"]["depth_m"].as<double>();
  sb["center_ne"] = vec2(centre.x(), centre.y());
  sb["size_m"] = vec2(side, side);
  sb["resolution_m"] = res;
  sb.remove("heightmap");
  sb["relief"]["amplitude_m"] = s["seabed"]["relief_m"].as<double>();
  sb["relief"]["wavelength_m"] = s["seabed"]["relief_wavelength_m"].as<double>();
  sb["relief"]["seed"] = static_cast<std::uint32_t>(seed % 1000033);
  sb["material"]["texture"] = s["seabed"]["texture"].as<std::string>();
  w["seabed"] = sb;

  // Rocks: a seeded field around the pipeline; the base world's hand-placed rocks and objects
  // belong to its own pipeline and are dropped.
  w.remove("rocks");
  YAML::Node rf = w["rock_field"] ? YAML::Clone(w["rock_field"]) : YAML::Node();
  rf["count"] = s["rocks"]["count"].as<int>();
  rf["seed"] = static_cast<std::uint32_t>(seed % 1000037);
  YAML::Node region(YAML::NodeType::Sequence);
  region.SetStyle(YAML::EmitterStyle::Flow);
  region.push_back(vec2(lo.x() - 8.0, lo.y() - 8.0));
  region.push_back(vec2(hi.x() + 8.0, hi.y() + 8.0));
  rf["region_ne"] = region;
  rf["radius_m"] = vec2(0.08, s["rocks"]["max_radius_m"].as<double>());
  rf["clearance_from_pipe_m"] = radius + 0.4;
  if (!rf["material"]) rf["material"]["texture"] = "rock";
  w["rock_field"] = rf;

  YAML::Node objects(YAML::NodeType::Sequence);
  const int n_objects = s["objects"]["count"].as<int>();
  Rng orng{KeySeed(seed, "objects.placement")};
  for (int i = 0; i < n_objects && !spec.object_meshes().empty(); ++i) {
    YAML::Node o;
    o["name"] = "object_" + std::to_string(i);
    o["mesh"] = spec.object_meshes()[orng.Next() % spec.object_meshes().size()];
    const double n = lo.x() - 5.0 + (hi.x() - lo.x() + 10.0) * orng.Uniform01();
    const double e = lo.y() - 5.0 + (hi.y() - lo.y() + 10.0) * orng.Uniform01();
    o["pose"]["xyz_m"] = vec3(n, e, s["seabed"]["depth_m"].as<double>() - 0.1);
    o["pose"]["rpy_deg"] = vec3(0.0, 0.0, 360.0 * orng.Uniform01());
    const double sc = s["objects"]["scale"].as<double>();
    o["scale"] = vec3(sc, sc, sc);
    o["class"] = "other";
    o["material"]["texture"] = "rock";
    objects.push_back(o);
  }
  w["objects"] = objects;

  // Lights: the sun from elevation/azimuth, lamps spread across the bow.
  const double el = s["sun"]["elevation_deg"].as<double>() * M_PI / 180.0;
  const double az = s["sun"]["azimuth_deg"].as<double>() * M_PI / 180.0;
  const double irr = s["sun"]["irradiance"].as<double>();
  YAML::Node lights = w["lights"] ? YAML::Clone(w["lights"]) : YAML::Node();
  lights["sun"]["direction_ned"] = vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  lights["sun"]["surface_irradiance"] = vec3(irr, irr, irr);
  if (!lights["sun"]["ambient_fraction"]) lights["sun"]["ambient_fraction"] = 0.4;
  YAML::Node lamps(YAML::NodeType::Sequence);
  const int n_lamps = s["lamps"]["count"].as<int>();
  const double li = s["lamps"]["intensity"].as<double>();
  for (int i = 0; i < n_lamps; ++i) {
    YAML::Node l;
    l["name"] = "lamp_" + std::to_string(i);
    const double y = n_lamps == 1 ? 0.0 : -0.15 + 0.3 * i / (n_lamps - 1);
    l["mount"]["xyz_m"] = vec3(0.2, y, 0.05);
    l["mount"]["rpy_deg"] = vec3(0.0, -30.0, 0.0);
    l["half_angle_deg"] = s["lamps"]["half_angle_deg"].as<double>();
    l["intensity"] = vec3(li, 0.95 * li, 0.87 * li);
    lamps.push_back(l);
  }
  lights["lamps"] = lamps;
  w["lights"] = lights;

  // Current: a constant current file beside the world.
  w.remove("current");
  const double speed = s["current"]["speed_mps"].as<double>();
  if (speed > 0.0) {
    const double dir_rad = s["current"]["direction_deg"].as<double>() * M_PI / 180.0;
    YAML::Node cur;
    cur["current"]["type"] = "constant";
    cur["current"]["velocity"] = vec3(speed * std::cos(dir_rad), speed * std::sin(dir_rad), 0.0);
    out.current_file = (fs::path(dir) / "current.yaml").string();
    write_yaml(out.current_file, cur, "# Constant current of this randomized sample (NED, m/s).\n");
    w["current"]["file"] = "current.yaml";
  }

  out.world_file = (fs::path(dir) / "world.yaml").string();
  write_yaml(out.world_file, w,
             "# Randomized sample world (seed " + std::to_string(seed) + "), written by unav datagen.\n");
  return out;
}

std::vector<PathPoint> plan_trajectory(const YAML::Node& s, const unav::scene::World& world, double step_m) {
  if (world.pipelines.empty() || world.pipelines[0].centerline_W.size() < 2)
    throw DatasetError("plan_trajectory: the sample world has no pipeline");
  const auto& line = world.pipelines[0].centerline_W;
  const std::string kind = s["trajectory"]["kind"].as<std::string>();
  const double alt = s["trajectory"]["altitude_m"].as<double>();
  std::vector<Eigen::Vector2d> poly;
  if (kind == "follow_pipe") {
    const double off = s["trajectory"]["lateral_offset_m"].as<double>();
    for (size_t i = 0; i < line.size(); ++i) {
      const Eigen::Vector3d t = (line[std::min(i + 1, line.size() - 1)] - line[i > 0 ? i - 1 : 0]).normalized();
      const Eigen::Vector2d right(-t.y(), t.x());
      poly.push_back(line[i].head<2>() + off * right);
    }
  } else {
    Eigen::Vector2d lo = line[0].head<2>(), hi = lo;
    for (const auto& p : line) {
      lo = lo.cwiseMin(p.head<2>());
      hi = hi.cwiseMax(p.head<2>());
    }
    lo -= Eigen::Vector2d(2.0, 2.0);
    hi += Eigen::Vector2d(2.0, 2.0);
    if (kind == "lawnmower") {
      const double spacing = s["trajectory"]["lane_spacing_m"].as<double>();
      bool up = true;
      for (double e = lo.y(); e <= hi.y() + 1e-9; e += spacing) {
        poly.emplace_back(up ? lo.x() : hi.x(), e);
        poly.emplace_back(up ? hi.x() : lo.x(), e);
        up = !up;
      }
    } else {
      Rng rng{KeySeed(s["seed"].as<std::uint64_t>(), "trajectory.random_waypoints")};
      const int n = s["trajectory"]["waypoints"].as<int>();
      for (int i = 0; i < n; ++i)
        poly.emplace_back(lo.x() + (hi.x() - lo.x()) * rng.Uniform01(), lo.y() + (hi.y() - lo.y()) * rng.Uniform01());
    }
  }
  // Resample every step_m along the polyline; heading along the path.
  std::vector<PathPoint> out;
  double next = 0.0, travelled = 0.0;  // arc length of the next point, of the segment start
  for (size_t i = 0; i + 1 < poly.size(); ++i) {
    const Eigen::Vector2d a = poly[i], b = poly[i + 1];
    const double L = (b - a).norm();
    if (L < 1e-9) continue;
    const double yaw = std::atan2(b.y() - a.y(), b.x() - a.x());
    for (; next <= travelled + L; next += step_m) {
      const Eigen::Vector2d p = a + (b - a) * ((next - travelled) / L);
      PathPoint pp;
      pp.yaw = yaw;
      pp.p_W = Eigen::Vector3d(p.x(), p.y(), world.seabed.depth_at(p.x(), p.y()) - alt);
      out.push_back(pp);
    }
    travelled += L;
  }
  if (out.empty()) throw DatasetError("plan_trajectory: empty path");
  return out;
}

}  // namespace unav::datagen

#include "unav_datagen/randomization.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "unav_common/errors.hpp"
#include "unav_datagen/dataset_writer.hpp"
#include "unav_scene/noise.hpp"
#include "unav_scene/scenario.hpp"

namespace fs = std::filesystem;

namespace unav::datagen {
namespace {

// A path key of a sample: absolute, or relative to the spec's folder, then under the resource
// roots' config/ and top (as a scenario resolves its files).
void resolve(std::string* value, const std::string& dir, const std::string& file, const std::string& key) {
  *value = unav::scene::find_scenario_file(*value, dir, file, key);
}

}  // namespace

std::string RandomizationSpec::documentation() {
  std::ostringstream o;
  std::string section = "-";
  for (const auto& f : unav::common::Describe(DatagenSample{})) {
    if (f.type == "mapping") continue;  // a section's own row: its fields follow
    const auto dot = f.name.find('.');
    const std::string s = dot == std::string::npos ? "(top level)" : f.name.substr(0, dot);
    if (s != section) {
      section = s;
      o << "\n### " << s << "\n\n| key | type | rule | default | unit | meaning |\n|---|---|---|---|---|---|\n";
    }
    auto cell = [](const std::string& v) { return v.empty() ? std::string("-") : v; };
    o << "| `" << f.name << "` | " << f.type << " | " << cell(f.rule) << " | `" << f.default_value << "` | "
      << cell(f.unit) << " | " << cell(f.doc) << " |\n";
  }
  return o.str();
}

RandomizationSpec RandomizationSpec::load(const std::string& path) {
  return parse(unav::common::detail::ReadYamlFile(path), path);
}

RandomizationSpec RandomizationSpec::parse(const YAML::Node& root, const std::string& file) {
  RandomizationSpec spec{unav::common::Stochastic<DatagenSample>(root, file)};
  const YAML::Node seed = spec.root()["seed"];
  if (seed.IsDefined() && unav::common::IsDistribution(seed))
    throw unav::ConfigError(file, "seed", "", "the base seed must be a fixed value (sample k uses seed + k)");
  // Read by the schema (a decimal integer; "0999" is 999, not octal).
  spec.base_seed_ = static_cast<std::uint64_t>(spec.spec_.Sample(0).seed);
  (void)spec.sample(0);  // paths, presets and cross-field rules, before any work
  return spec;
}

DatagenSample RandomizationSpec::sample_seed(std::uint64_t seed) const {
  DatagenSample s = spec_.Sample(seed);
  s.seed = static_cast<int64_t>(seed);
  const std::string& f = file();
  const std::string dir = fs::path(f).parent_path().string();
  resolve(&s.base_world, dir, f, "base_world");
  resolve(&s.cameras_config, dir, f, "cameras_config");
  resolve(&s.sonars_config, dir, f, "sonars_config");
  s.world.enabled = true;
  unav::scene::check_world_generator(s.world, f, "world.");
  unav::scene::resolve_world_generator_paths(&s.world, dir, f, "world.");
  return s;
}

std::string write_sample_current(const DatagenSample& s, const std::string& dir) {
  if (!(s.current.speed_mps > 0.0)) return "";
  const double a = s.current.direction_deg * M_PI / 180.0;
  YAML::Node cur;
  cur["current"]["type"] = "constant";
  YAML::Node v(YAML::NodeType::Sequence);
  v.SetStyle(YAML::EmitterStyle::Flow);
  v.push_back(s.current.speed_mps * std::cos(a));
  v.push_back(s.current.speed_mps * std::sin(a));
  v.push_back(0.0);
  cur["current"]["velocity"] = v;
  fs::create_directories(dir);
  std::string path = (fs::path(dir) / "current.yaml").string();
  std::ofstream out(path);
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << cur;
  out << "# Constant current of this randomized sample (NED, m/s).\n" << e.c_str() << "\n";
  out.flush();
  if (!out) throw DatasetError(path + ": cannot write");
  return path;
}

std::vector<PathPoint> plan_trajectory(const DatagenSample& s, const unav::scene::World& world, double step_m) {
  if (world.pipelines.empty() || world.pipelines[0].centerline_W.size() < 2)
    throw DatasetError("plan_trajectory: the sample world has no pipeline");
  const auto& line = world.pipelines[0].centerline_W;
  const std::string& kind = s.trajectory.kind;
  const double alt = s.trajectory.altitude_m;
  std::vector<Eigen::Vector2d> poly;
  if (kind == "follow_pipe") {
    const double off = s.trajectory.lateral_offset_m;
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
      const double spacing = s.trajectory.lane_spacing_m;
      bool up = true;
      for (double e = lo.y(); e <= hi.y() + 1e-9; e += spacing) {
        poly.emplace_back(up ? lo.x() : hi.x(), e);
        poly.emplace_back(up ? hi.x() : lo.x(), e);
        up = !up;
      }
    } else {
      unav::common::SplitMix64 rng{
          unav::common::KeySeed(static_cast<std::uint64_t>(s.seed), "trajectory.random_waypoints")};
      const int n = s.trajectory.waypoints;
      for (int i = 0; i < n; ++i)
        poly.emplace_back(lo.x() + (hi.x() - lo.x()) * rng.Uniform01(), lo.y() + (hi.y() - lo.y()) * rng.Uniform01());
    }
  }
  // Resample every step_m along the polyline; heading along the path, off it by the pilot's wander:
  // smooth noise of the arc length (value noise, one lattice value every wander_length_m, mapped
  // to [-1, 1)), its own seed per component.
  const auto seed32 = static_cast<std::uint32_t>(
      unav::common::KeySeed(static_cast<std::uint64_t>(s.seed), "trajectory.wander") & 0xFFFFFFFFu);
  auto wander = [&](double arc, std::uint32_t component) {
    return 2.0 * unav::scene::noise::fbm2(arc / s.trajectory.wander_length_m, 0.5, seed32 + 7919U * component, 1) - 1.0;
  };
  const double yaw_wander = s.trajectory.heading_wander_deg * M_PI / 180.0;
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
      pp.yaw = yaw + (yaw_wander > 0.0 ? yaw_wander * wander(next, 0) : 0.0);
      // Never closer to the seabed than 0.3 m (the DVL's and the contact's margin).
      const double dz = s.trajectory.altitude_wander_m > 0.0
                            ? std::min(s.trajectory.altitude_wander_m * wander(next, 1), alt - 0.3)
                            : 0.0;
      pp.p_W = Eigen::Vector3d(p.x(), p.y(), world.seabed.depth_at(p.x(), p.y()) - alt - dz);
      out.push_back(pp);
    }
    travelled += L;
  }
  if (out.empty()) throw DatasetError("plan_trajectory: empty path");
  return out;
}

}  // namespace unav::datagen

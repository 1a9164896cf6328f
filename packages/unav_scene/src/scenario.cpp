#include "unav_scene/scenario.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_common/sampling.hpp"

namespace fs = std::filesystem;

namespace unav::scene {
namespace {

// `value` as an absolute path: itself, under `dir`, or under the resource roots (first with
// each of `prefixes`, e.g. "config/"). Throws ConfigError naming the key when none exists.
std::string resolve(const std::string& value, const std::string& dir, const std::vector<std::string>& prefixes,
                    const std::string& file, const std::string& key) {
  if (value.empty()) throw unav::ConfigError(file, key, "\"\"", "a file path is required");
  const fs::path p(value);
  if (p.is_absolute()) {
    if (!fs::exists(p)) throw unav::ConfigError(file, key, value, "no such file");
    return value;
  }
  if (!dir.empty() && fs::exists(fs::path(dir) / p)) return fs::absolute(fs::path(dir) / p).lexically_normal().string();
  for (const auto& prefix : prefixes)
    if (auto r = unav::common::try_find_resource(prefix + value)) return fs::absolute(*r).lexically_normal().string();
  std::string where = dir.empty() ? std::string() : dir + "/, ";
  for (std::size_t i = 0; i < prefixes.size(); ++i)
    where += (i ? ", " : "") + std::string("the resource roots' ") + (prefixes[i].empty() ? "top" : prefixes[i]);
  throw unav::ConfigError(file, key, value, "no such file (looked under " + where + ")");
}

}  // namespace

std::string find_scenario_file(const std::string& value, const std::string& dir, const std::string& file,
                               const std::string& key) {
  return resolve(value, dir, {"config/", ""}, file, key);
}

void resolve_scenario_paths(Scenario* s, const std::string& file, const std::string& dir) {
  const std::vector<std::string> config{"config/", ""}, top{"", "config/"};
  s->world = resolve(s->world, dir, top, file, "world");
  // A water preset is a name ("3C", "jerlov_II"); a file has a '/' or ends in .yaml.
  if (s->water.find('/') != std::string::npos || s->water.find(".yaml") != std::string::npos)
    s->water = resolve(s->water, dir, config, file, "water");
  if (!s->current.empty()) s->current = resolve(s->current, dir, config, file, "current");
  s->vehicle.model = resolve(s->vehicle.model, dir, config, file, "vehicle.model");
  std::set<std::string> names;
  for (size_t i = 0; i < s->fleet.size(); ++i) {
    auto& f = s->fleet[i];
    const std::string key = "fleet[" + std::to_string(i) + "]";
    const bool valid = !f.name.empty() && std::isalpha(static_cast<unsigned char>(f.name[0])) &&
                       std::all_of(f.name.begin(), f.name.end(),
                                   [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (!valid)
      throw unav::ConfigError(file, key + ".name", "\"" + f.name + "\"",
                              "a namespace: a letter, then letters, digits or _");
    if (!names.insert(f.name).second)
      throw unav::ConfigError(file, key + ".name", f.name, "each fleet vehicle needs a namespace of its own");
    f.vehicle.model = resolve(f.vehicle.model, dir, config, file, key + ".model");
  }
  s->control.mpc = resolve(s->control.mpc, dir, config, file, "control.mpc");
  s->control.allocator = resolve(s->control.allocator, dir, config, file, "control.allocator");
  s->cameras.config = resolve(s->cameras.config, dir, config, file, "cameras.config");
  if (s->generate.enabled) {
    check_world_generator(s->generate, file, "generate.");
    resolve_world_generator_paths(&s->generate, dir, file, "generate.");
  }
  if (!s->sonars.names.empty()) s->sonars.config = resolve(s->sonars.config, dir, config, file, "sonars.config");
  if ((s->cameras.width > 0) != (s->cameras.height > 0))
    throw unav::ConfigError(file, "cameras.width/cameras.height",
                            std::to_string(s->cameras.width) + "x" + std::to_string(s->cameras.height),
                            "give both or neither");
  const double ratio = s->control.period / s->physics.dt;
  if (std::abs(ratio - std::round(ratio)) > 1e-6 * ratio)
    throw unav::ConfigError(file, "control.period", std::to_string(s->control.period),
                            "must be a whole number of physics.dt steps (" + std::to_string(s->physics.dt) + " s)");
}

Scenario parse_scenario(const YAML::Node& root, const std::string& file, const std::string& dir,
                        std::optional<std::uint64_t> seed) {
  const unav::common::Stochastic<Scenario> spec(root, file);
  if (!seed) {
    const YAML::Node s = spec.spec().IsMap() ? spec.spec()["seed"] : YAML::Node();
    if (s.IsDefined() && unav::common::IsDistribution(s))
      throw unav::ConfigError(file, "seed", "", "the seed that draws the distributions must be a fixed value");
    seed = s.IsDefined() ? s.as<std::uint64_t>() : 0;
  }
  YAML::Node concrete = spec.SampledYaml(*seed);
  concrete["seed"] = static_cast<int64_t>(*seed);
  Scenario out;
  unav::common::LoadYaml(concrete, file, &out);
  resolve_scenario_paths(&out, file, dir);
  return out;
}

YAML::Node apply_scenario_overrides(const YAML::Node& root, const std::vector<std::string>& overrides,
                                    const std::string& file) {
  YAML::Node out = YAML::Clone(root);
  if (!out.IsDefined() || out.IsNull()) out = YAML::Node(YAML::NodeType::Map);
  for (const auto& o : overrides) {
    const auto eq = o.find('=');
    const std::string path = o.substr(0, eq);
    if (eq == std::string::npos || path.empty() || path.front() == '.' || path.back() == '.' ||
        path.find("..") != std::string::npos)
      throw unav::ConfigError(file, "scenario_set", o, "each override is key.path=value (e.g. water=3C)");
    YAML::Node value(std::string{});  // "key=" is the empty string (e.g. water= : the world's)
    try {
      if (eq + 1 < o.size()) value = YAML::Load(o.substr(eq + 1));
    } catch (const YAML::Exception& e) {
      throw unav::ConfigError(file, path, o.substr(eq + 1), std::string("the value must be YAML: ") + e.msg);
    }
    if (!out.IsMap()) throw unav::ConfigError(file, path, o, "the scenario must be a map to override its keys");
    YAML::Node cur = out;  // yaml-cpp: reset() rebinds, operator= would overwrite the node
    std::size_t begin = 0;
    for (std::size_t dot = path.find('.'); dot != std::string::npos; dot = path.find('.', begin)) {
      const std::string key = path.substr(begin, dot - begin);
      if (!cur[key].IsDefined() || cur[key].IsNull()) cur[key] = YAML::Node(YAML::NodeType::Map);
      if (!cur[key].IsMap())
        throw unav::ConfigError(file, path.substr(0, dot), o, "is not a section: only keys of sections can be set");
      YAML::Node next = cur[key];
      cur.reset(next);
      begin = dot + 1;
    }
    cur[path.substr(begin)] = value;
  }
  return out;
}

Scenario load_scenario(const std::string& path, std::optional<std::uint64_t> seed,
                       const std::vector<std::string>& overrides) {
  const YAML::Node root = unav::common::detail::ReadYamlFile(path);
  if (overrides.empty()) return parse_scenario(root, path, fs::path(path).parent_path().string(), seed);
  // Errors of an overridden file name it with its overrides: the value at fault may be either's.
  std::string label = path + " (scenario_set:";
  for (const auto& o : overrides) label += " " + o;
  label += ")";
  return parse_scenario(apply_scenario_overrides(root, overrides, label), label, fs::path(path).parent_path().string(),
                        seed);
}

Scenario ScenarioParam::load() const { return load_scenario_param(file, seed, overrides); }

Scenario load_scenario_param(const std::string& path, int64_t seed, const std::vector<std::string>& overrides) {
  return load_scenario(path, seed >= 0 ? std::optional<std::uint64_t>(seed) : std::nullopt, overrides);
}

std::vector<CameraModel> scenario_cameras(const Scenario& s) {
  if (s.cameras.names.empty()) throw unav::ConfigError(s.name, "cameras.names", "[]", "at least one camera to render");
  std::vector<CameraModel> out;
  for (const auto& name : s.cameras.names)
    out.push_back(scale_camera(load_camera(s.cameras.config, name), s.cameras.width, s.cameras.height));
  return out;
}

World scenario_world(const Scenario& s) {
  World w = load_world(s.world);
  if (s.generate.enabled) w = generate_world(s.generate, w, static_cast<std::uint64_t>(s.seed));
  if (!s.water.empty()) w.water = load_water_spec(s.water);
  return w;
}

World pipeline_world(const ScenarioParam& scenario, const std::string& world_file) {
  std::string file = world_file;
  World w;
  if (scenario.given()) {
    const Scenario sc = scenario.load();
    file = sc.world;
    w = scenario_world(sc);
  } else {
    w = load_world(world_file);
  }
  if (w.pipelines.empty()) throw ConfigError("pipeline_world '" + file + "' has no pipeline");
  return w;
}

YAML::Node scenario_yaml(const Scenario& s) { return unav::common::ToYaml(s); }

}  // namespace unav::scene

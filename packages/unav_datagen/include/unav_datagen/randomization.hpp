// Domain randomization as a declarative spec (config/datagen/*.yaml): every key is either a fixed
// value or a distribution,
//   {uniform: [lo, hi]}                 real, lo <= hi
//   {normal: {mean: m, std: s}}         real, clipped to the key's valid range
//   {int: [lo, hi]}                     integer, both ends included
//   {choice: [a, b, ...]}               one of the listed values, equally likely
// validated on load (unknown key, empty range, unknown distribution, a value or support outside
// the key's rule, an unknown water preset: ConfigError naming file, key, value and rule) before
// any work starts. Sample k of a spec uses seed `seed + k`; each key draws from its own generator
// seeded from (sample seed, key path), so a sample is reproduced bit for bit by its seed and adding
// a key to a spec does not change the others. The distributions are implemented here (not
// <random>'s, whose algorithms differ between standard libraries).
//
// A resolved sample is a YAML map with the spec's keys and concrete values; write_sample_world()
// turns it into a world.yaml (and current.yaml) that scene::load_world() and the DDS launch
// (`world:=`) both read, and plan_trajectory() into the path the vehicle flies.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "unav_scene/world.hpp"

namespace unav::datagen {

/// One key of the spec language, for documentation (`unav datagen --spec-help`).
struct SpecKey {
  std::string path;      ///< e.g. "water.turbidity"
  std::string type;      ///< "real", "int", "string", "path"
  std::string rule;      ///< e.g. "in (0, 10]", "one of: tum, euroc, kitti"
  std::string fallback;  ///< value when the spec leaves the key out
  std::string doc;
  bool randomizable = true;
};

class RandomizationSpec {
 public:
  /// Loads and validates a spec file. Throws unav::ConfigError (file, key, value, rule).
  static RandomizationSpec load(const std::string& path);
  /// Validates a parsed spec; `file` names it in errors, relative paths resolve against its folder.
  static RandomizationSpec parse(const YAML::Node& root, const std::string& file);

  /// Every key of the language, in the order samples draw them.
  static const std::vector<SpecKey>& keys();
  /// keys() as Markdown (a table per section), for docs/datagen.md and --spec-help.
  static std::string documentation();

  /// The seed of sample `index`: base seed + index.
  std::uint64_t seed_of(std::uint64_t index) const { return base_seed_ + index; }
  /// The resolved sample drawn with `seed` (a map of sections; a per-segment key gives a list).
  YAML::Node sample_seed(std::uint64_t seed) const;
  YAML::Node sample(std::uint64_t index) const { return sample_seed(seed_of(index)); }

  const std::string& file() const { return file_; }
  /// base_world and cameras_config as absolute paths; objects.folder too ("" = none).
  const std::string& base_world() const { return base_world_; }
  const std::string& cameras_config() const { return cameras_config_; }
  const std::string& sonars_config() const { return sonars_config_; }
  const std::string& objects_folder() const { return objects_folder_; }
  /// Meshes in objects.folder (sorted), chosen from by samples.
  const std::vector<std::string>& object_meshes() const { return object_meshes_; }
  /// The spec as written (for the manifest and job scripts).
  const YAML::Node& root() const { return root_; }

 private:
  struct Leaf;
  std::string file_, base_world_, cameras_config_, sonars_config_, objects_folder_;
  std::vector<std::string> object_meshes_;
  std::uint64_t base_seed_ = 0;
  YAML::Node root_;
  std::vector<YAML::Node> leaves_;  // per keys() entry: the fixed value or distribution node
};

/// Files of one resolved sample: `dir`/world.yaml and, with a current, `dir`/current.yaml.
struct SampleWorld {
  std::string world_file;
  std::string current_file;  ///< "" = still water
};
/// Writes the sample's world (base world with the randomized water, seabed, pipeline, rocks,
/// objects, lights and current) into `dir`. Throws unav::ConfigError / DatasetError.
SampleWorld write_sample_world(const RandomizationSpec& spec, const YAML::Node& sample, const std::string& dir);

/// A point of the vehicle's path: position (world_ned) and heading.
struct PathPoint {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  double yaw = 0.0;  ///< rad, NED (0 = north)
};
/// The path of the sample's trajectory (follow_pipe, lawnmower or random_waypoints) over the
/// loaded sample world, sampled every `step_m` metres, at trajectory.altitude_m above the seabed.
std::vector<PathPoint> plan_trajectory(const YAML::Node& sample, const unav::scene::World& world, double step_m);

}  // namespace unav::datagen

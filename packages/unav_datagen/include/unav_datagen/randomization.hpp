// Domain randomization for `unav datagen` (config/datagen/*.yaml): a typed spec whose every field
// may be a distribution of the one sampler (unav_common/sampling.hpp: {uniform}, {normal}, {int},
// {choice}, and {repeat} for lists), checked on load (unknown key, empty range, a distribution's
// support outside its field's rule, an unknown water preset, a missing file: ConfigError naming
// file, key, value and rule) before any work starts. Its world is the one pipe-world generator's
// spec (scene::WorldGenerator, the same language as a scenario's `generate:` and the gym's
// `pipe_scenes:`), laid over base_world. Sample k uses seed `seed + k`; each field draws from its
// own generator seeded from (sample seed, key path), so a sample is reproduced bit for bit by its
// seed and adding a key to a spec does not change the others.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "unav_common/config.hpp"
#include "unav_common/sampling.hpp"
#include "unav_scene/render_settings.hpp"
#include "unav_scene/world.hpp"
#include "unav_scene/world_generator.hpp"

namespace unav::datagen {

struct DatagenOutput {
  std::string format = "tum";
  std::string camera = "down";
  int width = 640;
  int height = 480;
  int frames = 100;
  double rate_hz = 10.0;
  std::string sonar;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("format", &format).OneOf({"tum", "euroc", "kitti"}).Doc("dataset layout"));
    a->Visit(Field("camera", &camera).Doc("camera of cameras_config to render"));
    a->Visit(Field("width", &width).Range(16, 4096).Unit("px").Doc("image width (intrinsics scaled)"));
    a->Visit(Field("height", &height).Range(16, 4096).Unit("px"));
    a->Visit(Field("frames", &frames).Range(1, 1000000).Doc("frames per sample"));
    a->Visit(Field("rate_hz", &rate_hz).Above(0.0).Max(100.0).Unit("Hz").Doc("camera frame rate"));
    a->Visit(Field("sonar", &sonar).Doc("sonar of sonars_config pinged along the flight (\"\" = none)"));
  }
};

/// A constant water current (written as the sample's current.yaml).
struct DatagenCurrent {
  double speed_mps = 0.0;
  double direction_deg = 0.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("speed_mps", &speed_mps).Range(0.0, 3.0).Unit("m/s").Doc("constant current speed"));
    a->Visit(
        Field("direction_deg", &direction_deg).Range(-360.0, 360.0).Unit("deg").Doc("it flows towards, from north"));
  }
};

struct DatagenCamera {
  double noise_stddev = 0.0;
  double exposure = 1.0;
  double gain = 1.0;
  int jpeg_quality = 0;
  std::string white_balance = "off";

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("noise_stddev", &noise_stddev).Range(0.0, 0.5).Doc("read noise (0..1 of full scale)"));
    a->Visit(Field("exposure", &exposure).Above(0.0).Max(20.0).Doc("exposure (linear)"));
    a->Visit(Field("gain", &gain).Above(0.0).Max(16.0).Doc("gain: scales exposure and noise"));
    a->Visit(Field("jpeg_quality", &jpeg_quality).Range(0, 100).Doc("JPEG compression of the frames; 0 = none"));
    a->Visit(Field("white_balance", &white_balance)
                 .OneOf({"off", "auto"})
                 .Doc("auto: balanced for the light at the camera's depth"));
  }
};

struct DatagenTrajectory {
  std::string kind = "follow_pipe";
  double altitude_m = 1.5;
  double speed_mps = 0.3;
  double lateral_offset_m = 0.0;
  double lane_spacing_m = 3.0;
  int waypoints = 6;
  double heading_wander_deg = 0.0;
  double altitude_wander_m = 0.0;
  double wander_length_m = 4.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("kind", &kind).OneOf({"follow_pipe", "lawnmower", "random_waypoints"}).Doc("path flown"));
    a->Visit(Field("altitude_m", &altitude_m).Range(0.3, 50.0).Unit("m").Doc("height above the seabed"));
    a->Visit(Field("speed_mps", &speed_mps).Above(0.0).Max(3.0).Unit("m/s").Doc("speed along the path"));
    a->Visit(Field("lateral_offset_m", &lateral_offset_m).Range(-10.0, 10.0).Unit("m").Doc("follow_pipe: + = right"));
    a->Visit(Field("lane_spacing_m", &lane_spacing_m).Range(0.5, 50.0).Unit("m").Doc("lawnmower lanes"));
    a->Visit(Field("waypoints", &waypoints).Range(2, 100).Doc("random_waypoints: how many"));
    a->Visit(Field("heading_wander_deg", &heading_wander_deg)
                 .Range(0.0, 90.0)
                 .Unit("deg")
                 .Doc("a pilot's heading corrections: smooth random yaw off the path, up to this much"));
    a->Visit(Field("altitude_wander_m", &altitude_wander_m)
                 .Range(0.0, 5.0)
                 .Unit("m")
                 .Doc("smooth random altitude changes, up to this much either way"));
    a->Visit(Field("wander_length_m", &wander_length_m)
                 .Above(0.0)
                 .Max(100.0)
                 .Unit("m")
                 .Doc("path length over which the wander changes (its correlation length)"));
  }
};

/// Resources of each Slurm array task (`unav datagen --backend slurm`).
struct SlurmResources {
  int cpus_per_task = 1;
  std::string mem = "4G";
  std::string time = "01:00:00";
  std::string partition;
  std::string gres;
  int array_size = 0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("cpus_per_task", &cpus_per_task).Range(1, 1024));
    a->Visit(Field("mem", &mem).Doc("sbatch --mem"));
    a->Visit(Field("time", &time).Doc("sbatch --time"));
    a->Visit(Field("partition", &partition).Doc("\"\" = the cluster's default"));
    a->Visit(Field("gres", &gres).Doc("sbatch --gres, e.g. gpu:1"));
    a->Visit(Field("array_size", &array_size).Range(0, 1000000).Doc("tasks; 0 = one per sample"));
  }
};

/// A spec, and once drawn, one concrete sample of it.
struct DatagenSample {
  std::string description;
  int64_t seed = 0;  ///< in the spec: the base seed; in a sample: the sample's (base + index)
  std::string base_world = "worlds/pipe_inspection/world.yaml";
  std::string cameras_config = "config/sensors/bluerov2_cameras.yaml";
  std::string sonars_config = "config/sensors/bluerov2_sonars.yaml";
  DatagenOutput output;
  scene::WorldGenerator world;
  DatagenCurrent current;
  DatagenCamera camera;
  scene::RenderSettings render;
  DatagenTrajectory trajectory;
  SlurmResources slurm;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("description", &description));
    a->Visit(Field("seed", &seed).Range(0.0, 9007199254740992.0).Doc("base seed: sample k uses seed + k"));
    a->Visit(Field("base_world", &base_world).Doc("world the samples are generated over (materials, lamps, sun)"));
    a->Visit(Field("cameras_config", &cameras_config).Doc("camera set (mounts, intrinsics)"));
    a->Visit(Field("sonars_config", &sonars_config).Doc("sonar set for output.sonar"));
    a->Visit(Field("output", &output));
    a->Visit(Field("world", &world).Doc("the generated world (scene::WorldGenerator; `enabled` is implied)"));
    a->Visit(Field("current", &current));
    a->Visit(Field("camera", &camera));
    a->Visit(Field("render", &render));
    a->Visit(Field("trajectory", &trajectory));
    a->Visit(Field("slurm", &slurm));
  }
};

class RandomizationSpec {
 public:
  /// Loads and checks a spec file. Throws unav::ConfigError (file, key, value, rule).
  static RandomizationSpec load(const std::string& path);
  /// Checks a parsed spec; `file` names it in errors, relative paths resolve against its folder.
  static RandomizationSpec parse(const YAML::Node& root, const std::string& file);

  /// Every key of the language as Markdown (a table per section), for docs/datagen.md and
  /// --spec-help.
  static std::string documentation();

  /// The seed of sample `index`: base seed + index.
  std::uint64_t seed_of(std::uint64_t index) const { return base_seed_ + index; }
  /// The concrete sample drawn with `seed`: paths absolute, cross-field rules checked.
  DatagenSample sample_seed(std::uint64_t seed) const;
  DatagenSample sample(std::uint64_t index) const { return sample_seed(seed_of(index)); }

  const std::string& file() const { return spec_.file(); }
  /// The spec as written (after the checks).
  const YAML::Node& root() const { return spec_.spec(); }

 private:
  explicit RandomizationSpec(const unav::common::Stochastic<DatagenSample>& spec) : spec_(spec) {}
  unav::common::Stochastic<DatagenSample> spec_;
  std::uint64_t base_seed_ = 0;
};

/// Writes `dir`/current.yaml (a constant current) for a sample with a current and returns its
/// path; "" for still water. Throws DatasetError.
std::string write_sample_current(const DatagenSample& s, const std::string& dir);

/// A point of the vehicle's path: position (world_ned) and heading.
struct PathPoint {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  double yaw = 0.0;  ///< rad, NED (0 = north)
};
/// The path of the sample's trajectory (follow_pipe, lawnmower or random_waypoints) over the
/// sample's world, sampled every `step_m` metres, at trajectory.altitude_m above the seabed.
std::vector<PathPoint> plan_trajectory(const DatagenSample& s, const scene::World& world, double step_m);

}  // namespace unav::datagen

// The one generator of randomized pipe worlds (DESIGN.md section 9): a typed spec of a pipeline
// (a first run, then legs that each turn and run), the seabed around it, a rock field, the water,
// the light and scattered meshes, laid over a base world (materials, lamps, sun colour, marine
// snow particles). The spec's fields are concrete values; randomization is the one sampler's job
// (unav_common/sampling.hpp): written in a scenario (`generate:`), a learning config (the gym's
// `pipe_scenes:`) or a datagen spec (`world:`), any field may be a distribution and the legs a
// {repeat: ...}, e.g.
//   pipeline:
//     heading_deg: {uniform: [0, 360]}
//     legs: {repeat: {count: {int: [0, 3]}, each: {turn_deg: {uniform: [-75, 75]}, length_m: {uniform: [4, 9]}}}}
// generate_world(spec, base, seed) is deterministic: the seeds of the relief, the rocks, the
// marine snow and the object placement are KeySeed(seed, "generate.<part>").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "unav_common/config.hpp"
#include "unav_scene/world.hpp"

namespace unav::scene {

/// A turn of the pipeline followed by a straight run.
struct PipeLegSpec {
  double turn_deg = 0.0;  ///< heading change at the vertex, + = clockwise seen from above (north to east)
  double length_m = 6.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("turn_deg", &turn_deg).Range(-150.0, 150.0).Unit("deg").Doc("turn at the vertex, + = clockwise"));
    a->Visit(Field("length_m", &length_m).Above(0.0).Max(1000.0).Unit("m").Doc("straight run after the turn"));
  }
};

struct PipelineSpec {
  double heading_deg = 0.0;  ///< first run, clockwise from north
  double first_length_m = 7.0;
  std::vector<PipeLegSpec> legs;
  double radius_m = 0.25;
  double bend_radius_m = 0.0;  ///< centre-line radius of the bends; 0 = max(1.5 m, 4 radius_m)
  double burial_fraction = 0.2;
  double growth = 0.0;  ///< marine growth on the coating: 0 clean, 1 overgrown (darker, greener)

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("heading_deg", &heading_deg).Range(-360.0, 360.0).Unit("deg").Doc("first run, from north"));
    a->Visit(Field("first_length_m", &first_length_m).Above(0.0).Max(1000.0).Unit("m").Doc("first straight run"));
    a->Visit(Field("legs", &legs).Doc("then, in order: turn, run"));
    a->Visit(Field("radius_m", &radius_m).Range(0.02, 2.0).Unit("m"));
    a->Visit(Field("bend_radius_m", &bend_radius_m).Range(0.0, 50.0).Unit("m").Doc("0 = max(1.5 m, 4 radius)"));
    a->Visit(Field("burial_fraction", &burial_fraction).Range(0.0, 0.95).Doc("share of the diameter below the seabed"));
    a->Visit(Field("growth", &growth).Range(0.0, 1.0).Doc("marine growth on the coating (darker, greener)"));
  }
};

/// The seabed: a patch around the pipeline (its bounding box plus margin_m, square, a whole
/// number of the base seabed's cells), the base's material with `texture` and `albedo`.
struct SeabedSpec {
  double depth_m = 10.0;
  double relief_m = 0.15;
  double relief_wavelength_m = 5.0;
  std::string texture;  ///< "" = the base world's
  double albedo = 1.0;  ///< multiplier of the base seabed's albedo
  double margin_m = 12.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("depth_m", &depth_m).Range(1.0, 1000.0).Unit("m").Doc("mean seabed depth"));
    a->Visit(Field("relief_m", &relief_m).Range(0.0, 5.0).Unit("m").Doc("relief amplitude"));
    a->Visit(Field("relief_wavelength_m", &relief_wavelength_m).Range(0.5, 100.0).Unit("m"));
    a->Visit(Field("texture", &texture).OneOf({"", "sand", "rock", "checker", "none"}).Doc("\"\" = the base's"));
    a->Visit(Field("albedo", &albedo).Range(0.0, 3.0).Doc("multiplier of the base seabed's albedo"));
    a->Visit(Field("margin_m", &margin_m).Range(0.0, 500.0).Unit("m").Doc("seabed beyond the pipeline"));
  }
};

/// A seeded rock field in the pipeline's bounding box plus 8 m, clear of the pipe.
struct RocksSpec {
  double per_100m2 = 4.0;
  Eigen::Vector2d radius_m{0.08, 0.45};  ///< smallest, largest

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("per_100m2", &per_100m2).Range(0.0, 100.0).Doc("rocks per 100 m^2"));
    a->Visit(Field("radius_m", &radius_m).Range(0.01, 5.0).Unit("m").Doc("[smallest, largest] rock radius"));
  }
};

struct WaterSpec {
  std::string preset;              ///< Jerlov preset ("IB", "jerlov_3C"); "" = the base world's water
  double turbidity = 1.0;          ///< factor on the attenuation, backscatter, diffuse and scattering
  double marine_snow_per_m3 = -1;  ///< particles per m^3; < 0 = the base world's

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("preset", &preset).Doc("Jerlov preset (I, IA, IB, II, III, 1C, 3C, 5C, 7C, 9C); \"\" = the base's"));
    a->Visit(Field("turbidity", &turbidity).Above(0.0).Max(10.0).Doc("factor on the water's coefficients"));
    a->Visit(Field("marine_snow_per_m3", &marine_snow_per_m3).Range(-1.0, 2000.0).Doc("< 0 = the base's"));
  }
};

struct LightSpec {
  double sun_elevation_deg = 70.0;
  double sun_azimuth_deg = 30.0;
  double sun_irradiance = 1.0;     ///< multiplier of the base's surface irradiance
  int lamp_count = -1;             ///< < 0 = the base's lamps; else spread across the bow like its first
  double lamp_intensity = 1.0;     ///< multiplier of the base lamps' intensity
  double lamp_half_angle_deg = 0;  ///< 0 = the base's

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("sun_elevation_deg", &sun_elevation_deg).Range(1.0, 90.0).Unit("deg"));
    a->Visit(Field("sun_azimuth_deg", &sun_azimuth_deg).Range(-360.0, 360.0).Unit("deg").Doc("from north"));
    a->Visit(Field("sun_irradiance", &sun_irradiance).Range(0.0, 10.0).Doc("multiplier of the base's"));
    a->Visit(Field("lamp_count", &lamp_count).Range(-1, 8).Doc("< 0 = the base's lamps"));
    a->Visit(Field("lamp_intensity", &lamp_intensity).Range(0.0, 20.0).Doc("multiplier of the base lamps'"));
    a->Visit(Field("lamp_half_angle_deg", &lamp_half_angle_deg).Range(0.0, 89.0).Unit("deg").Doc("0 = the base's"));
  }
};

/// Meshes of `folder` (.obj .ply .stl .gltf .glb .fbx .dae) scattered on the seabed near the pipe.
struct ObjectsSpec {
  std::string folder;  ///< absolute once resolved by the file that holds the spec
  int count = 0;
  double scale = 1.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("folder", &folder).Doc("folder of meshes; relative to the file or the resource roots"));
    a->Visit(Field("count", &count).Range(0, 1000).Doc("meshes placed (needs folder)"));
    a->Visit(Field("scale", &scale).Range(0.01, 100.0));
  }
};

struct WorldGenerator {
  bool enabled = false;  ///< in a scenario: generate the world over `world` (the base)
  PipelineSpec pipeline;
  SeabedSpec seabed;
  RocksSpec rocks;
  WaterSpec water;
  LightSpec light;
  ObjectsSpec objects;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("enabled", &enabled).Doc("generate the world over the base world"));
    a->Visit(Field("pipeline", &pipeline));
    a->Visit(Field("seabed", &seabed));
    a->Visit(Field("rocks", &rocks));
    a->Visit(Field("water", &water));
    a->Visit(Field("light", &light));
    a->Visit(Field("objects", &objects));
  }
};

/// Cross-field rules (a known water preset, rocks.radius_m ordered, a bend radius >= the pipe
/// radius, objects.count needs objects.folder, which must hold meshes); ConfigError naming
/// `file` and the key under `prefix` ("generate.", "world.").
void check_world_generator(const WorldGenerator& g, const std::string& file, const std::string& prefix);

/// Resolves objects.folder against `dir` and the resource roots (ConfigError when missing).
void resolve_world_generator_paths(WorldGenerator* g, const std::string& dir, const std::string& file,
                                   const std::string& prefix);

/// The world `g` describes over `base` (deterministic in `seed`): its pipeline starts at north =
/// east = 0; name, file and dir are the base's (relative paths resolve as in the base).
World generate_world(const WorldGenerator& g, const World& base, std::uint64_t seed);

}  // namespace unav::scene

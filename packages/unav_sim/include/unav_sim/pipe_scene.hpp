// Seeded generator of pipe-inspection scenes for learning and data generation: a pipeline of
// straight runs joined by bends (count, sign and angle of the turns, bend radii, burial, coating),
// the seabed (depth, relief, albedo), a rock field, the water (Jerlov presets), the light (sun
// irradiance and direction, lamp intensity) and marine snow, each drawn within the ranges of a
// config file (config/learning/pipe_scenes.yaml). Same seed and ranges, same World.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_scene/world.hpp"

namespace unav::sim {

/// Ranges are [min, max] (uniform draws) unless said otherwise.
struct PipeSceneRanges {
  /// World the lamps, materials and sun colour come from (relative to the resource roots).
  std::string base_world = "worlds/pipe_inspection/world.yaml";
  Eigen::Vector2d first_segment_m{5.0, 9.0};  ///< straight run before the first turn
  Eigen::Vector2d segment_m{4.0, 9.0};        ///< runs between turns and after the last
  std::vector<int> turns{0, 3};               ///< [min, max] number of turns (uniform integer)
  Eigen::Vector2d turn_deg{20.0, 75.0};       ///< turn angle magnitude; left or right at random
  Eigen::Vector2d bend_radius_m{0.8, 2.5};
  Eigen::Vector2d pipe_radius_m{0.15, 0.35};
  Eigen::Vector2d burial_fraction{0.0, 0.5};
  Eigen::Vector2d coating_albedo{0.55, 1.2};  ///< per-channel multiplier of the base coating
  bool random_heading = true;                 ///< first run's heading uniform in [0, 360) deg, else north
  Eigen::Vector2d seabed_depth_m{8.0, 14.0};
  Eigen::Vector2d relief_amplitude_m{0.0, 0.35};
  Eigen::Vector2d relief_wavelength_m{3.0, 9.0};
  Eigen::Vector2d seabed_albedo{0.6, 1.15};  ///< multiplier of the base seabed albedo
  Eigen::Vector2d rocks_per_100m2{0.0, 6.0};
  Eigen::Vector2d rock_radius_m{0.08, 0.5};  ///< the field's min and max rock radius (fixed)
  std::vector<std::string> waters{"I", "IA", "IB", "II", "III", "1C", "3C"};  ///< Jerlov presets, uniform
  Eigen::Vector2d sun_irradiance{0.6, 1.3};  ///< multiplier of the base surface irradiance
  Eigen::Vector2d sun_tilt_deg{0.0, 35.0};   ///< sun direction from the vertical, azimuth uniform
  Eigen::Vector2d lamp_intensity{0.4, 1.6};  ///< multiplier of the base lamps
  Eigen::Vector2d marine_snow_per_m3{0.0, 80.0};

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("base_world", &base_world).Doc("world.yaml giving lamps, materials and sun colour"));
    a->Visit(Field("first_segment_m", &first_segment_m).Above(0.0).Unit("m").Doc("straight run before the first turn"));
    a->Visit(Field("segment_m", &segment_m).Above(0.0).Unit("m").Doc("runs after each turn"));
    a->Visit(Field("turns", &turns).Range(0, 20).Doc("[min, max] number of turns"));
    a->Visit(Field("turn_deg", &turn_deg).Range(0.0, 120.0).Unit("deg").Doc("turn angle, sign at random"));
    a->Visit(Field("bend_radius_m", &bend_radius_m).Above(0.0).Unit("m"));
    a->Visit(Field("pipe_radius_m", &pipe_radius_m).Above(0.0).Max(2.0).Unit("m"));
    a->Visit(Field("burial_fraction", &burial_fraction).Range(0.0, 0.9).Doc("share of the diameter below the seabed"));
    a->Visit(Field("coating_albedo", &coating_albedo).Min(0.0).Doc("per-channel multiplier of the base coating"));
    a->Visit(Field("random_heading", &random_heading).Doc("first heading uniform, else north"));
    a->Visit(Field("seabed_depth_m", &seabed_depth_m).Above(1.0).Unit("m"));
    a->Visit(Field("relief_amplitude_m", &relief_amplitude_m).Min(0.0).Unit("m"));
    a->Visit(Field("relief_wavelength_m", &relief_wavelength_m).Above(0.0).Unit("m"));
    a->Visit(Field("seabed_albedo", &seabed_albedo).Min(0.0));
    a->Visit(Field("rocks_per_100m2", &rocks_per_100m2).Min(0.0).Max(100.0));
    a->Visit(Field("rock_radius_m", &rock_radius_m).Above(0.0).Unit("m"));
    a->Visit(Field("waters", &waters).Doc("Jerlov presets drawn uniformly (I, IA, IB, II, III, 1C, 3C, 5C, 7C, 9C)"));
    a->Visit(Field("sun_irradiance", &sun_irradiance).Min(0.0));
    a->Visit(Field("sun_tilt_deg", &sun_tilt_deg).Range(0.0, 80.0).Unit("deg"));
    a->Visit(Field("lamp_intensity", &lamp_intensity).Min(0.0));
    a->Visit(Field("marine_snow_per_m3", &marine_snow_per_m3).Min(0.0).Max(2000.0));
  }

  /// Cross-field rules (min <= max for every range, two turn counts, known water presets).
  /// Throws ConfigError naming `where` and the key.
  void validate(const std::string& where) const;
};

/// Reads `pipe_scenes:` of a learning config file (or the bare map), validated.
PipeSceneRanges load_pipe_scene_ranges(const std::string& path, const std::string& root = "pipe_scenes");

/// A randomized pipe world drawn from `ranges` with `seed` (the pipeline starts at north = east =
/// 0). `base`: the world of ranges.base_world (loaded by the caller once).
scene::World generate_pipe_world(const PipeSceneRanges& ranges, const scene::World& base, std::uint64_t seed);

}  // namespace unav::sim

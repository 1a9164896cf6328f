#include "unav_sim/pipe_scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "unav_common/errors.hpp"
#include "unav_scene/water.hpp"

namespace unav::sim {
namespace {

// Uniform draws from one seeded generator, in a fixed order (the order is part of the format:
// changing it changes every scene of a seed).
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed ^ 0x5DEECE66DULL) {}
  double uniform(const Eigen::Vector2d& r) { return r.x() + (r.y() - r.x()) * unit(); }
  double unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(rng_() >> 32U); }

 private:
  std::mt19937_64 rng_;
};

void check_range(const Eigen::Vector2d& r, const std::string& where, const std::string& key) {
  if (!(r.x() <= r.y()))
    throw ConfigError(where, key, "[" + std::to_string(r.x()) + ", " + std::to_string(r.y()) + "]", "need min <= max");
}

}  // namespace

void PipeSceneRanges::validate(const std::string& where) const {
  unav::common::Validate(*this, where);
  for (const auto& [key, r] :
       std::vector<std::pair<std::string, Eigen::Vector2d>>{{"first_segment_m", first_segment_m},
                                                            {"segment_m", segment_m},
                                                            {"turn_deg", turn_deg},
                                                            {"bend_radius_m", bend_radius_m},
                                                            {"pipe_radius_m", pipe_radius_m},
                                                            {"burial_fraction", burial_fraction},
                                                            {"coating_albedo", coating_albedo},
                                                            {"seabed_depth_m", seabed_depth_m},
                                                            {"relief_amplitude_m", relief_amplitude_m},
                                                            {"relief_wavelength_m", relief_wavelength_m},
                                                            {"seabed_albedo", seabed_albedo},
                                                            {"rocks_per_100m2", rocks_per_100m2},
                                                            {"rock_radius_m", rock_radius_m},
                                                            {"sun_irradiance", sun_irradiance},
                                                            {"sun_tilt_deg", sun_tilt_deg},
                                                            {"lamp_intensity", lamp_intensity},
                                                            {"marine_snow_per_m3", marine_snow_per_m3}})
    check_range(r, where, key);
  if (turns.size() != 2 || turns[0] > turns[1])
    throw ConfigError(where, "turns", std::to_string(turns.size()) + " values", "expected [min, max] with min <= max");
  if (!(bend_radius_m.x() >= pipe_radius_m.y()))
    throw ConfigError(where, "bend_radius_m", std::to_string(bend_radius_m.x()),
                      "the smallest bend radius must be >= the largest pipe radius (" +
                          std::to_string(pipe_radius_m.y()) + " m): a tighter bend folds the tube");
  if (waters.empty()) throw ConfigError(where, "waters", "[]", "at least one Jerlov preset");
  for (const auto& w : waters) {
    try {
      (void)scene::jerlov_preset(w);
    } catch (const std::exception& e) {
      throw ConfigError(where, "waters", w, e.what());
    }
  }
}

PipeSceneRanges load_pipe_scene_ranges(const std::string& path, const std::string& root) {
  PipeSceneRanges r;
  unav::common::LoadYamlFile(path, &r, root);
  r.validate(path);
  return r;
}

scene::World generate_pipe_world(const PipeSceneRanges& ranges, const scene::World& base, std::uint64_t seed) {
  Draw d(seed);
  scene::World w;
  w.name = "pipe_scene_" + std::to_string(seed);
  w.file = base.file;
  w.dir = base.dir;

  // Pipeline polyline in the north-east plane.
  const int turns = d.integer(ranges.turns[0], ranges.turns[1]);
  double heading = ranges.random_heading ? 2.0 * M_PI * d.unit() : 0.0;
  std::vector<Eigen::Vector2d> ne{Eigen::Vector2d::Zero()};
  double len = d.uniform(ranges.first_segment_m);
  for (int i = 0; i <= turns; ++i) {
    ne.push_back(ne.back() + len * Eigen::Vector2d(std::cos(heading), std::sin(heading)));
    if (i == turns) break;
    const double sign = d.unit() < 0.5 ? -1.0 : 1.0;
    heading += sign * d.uniform(ranges.turn_deg) * M_PI / 180.0;
    len = d.uniform(ranges.segment_m);
  }
  scene::Pipeline pipe;
  pipe.name = "main";
  pipe.radius_m = d.uniform(ranges.pipe_radius_m);
  pipe.bend_radius_m = std::max(pipe.radius_m, d.uniform(ranges.bend_radius_m));
  const double burial = d.uniform(ranges.burial_fraction);
  pipe.material = base.pipelines.empty() ? scene::Pipeline{}.material : base.pipelines.front().material;
  for (int k = 0; k < 3; ++k) pipe.material.albedo[k] *= d.uniform(ranges.coating_albedo);
  pipe.material.albedo = pipe.material.albedo.cwiseMin(1.0);

  // Seabed around the pipe's bounding box.
  Eigen::Vector2d lo = ne.front(), hi = ne.front();
  for (const auto& p : ne) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  w.seabed = base.seabed;
  w.seabed.heightmap_file.clear();
  w.seabed.hm_values.clear();
  w.seabed.hm_width = w.seabed.hm_height = 0;
  w.seabed.depth_m = d.uniform(ranges.seabed_depth_m);
  w.seabed.relief_amplitude_m = d.uniform(ranges.relief_amplitude_m);
  w.seabed.relief_wavelength_m = d.uniform(ranges.relief_wavelength_m);
  w.seabed.relief_seed = d.u32();
  const double albedo = d.uniform(ranges.seabed_albedo);
  w.seabed.material.albedo = (w.seabed.material.albedo * albedo).cwiseMin(1.0);
  const double margin = 20.0;
  w.seabed.center_ne = 0.5 * (lo + hi);
  w.seabed.size_m = (hi - lo).array() + 2.0 * margin;
  w.seabed.resolution_m = 1.0;

  for (const auto& p : ne)
    pipe.points_W.emplace_back(p.x(), p.y(), w.seabed.depth_at(p.x(), p.y()) - pipe.radius_m * (1.0 - 2.0 * burial));
  scene::build_centerline(&pipe);
  w.pipelines.push_back(std::move(pipe));

  // Rocks in the box around the pipe.
  scene::RockField field;
  field.region_lo_ne = lo.array() - 8.0;
  field.region_hi_ne = hi.array() + 8.0;
  const Eigen::Vector2d extent = field.region_hi_ne - field.region_lo_ne;
  field.count = static_cast<int>(std::lround(d.uniform(ranges.rocks_per_100m2) * extent.prod() / 100.0));
  field.seed = d.u32();
  field.radius_m = ranges.rock_radius_m;
  field.clearance_from_pipe_m = 0.4;
  if (!base.rocks.empty()) field.material = base.rocks.front().material;
  scene::add_rock_field(&w, field);

  // Water, light, particles.
  const auto& name = ranges.waters[static_cast<std::size_t>(d.integer(0, static_cast<int>(ranges.waters.size()) - 1))];
  w.water = scene::jerlov_preset(name);
  w.sun = base.sun;
  w.sun.surface_irradiance *= d.uniform(ranges.sun_irradiance);
  const double tilt = d.uniform(ranges.sun_tilt_deg) * M_PI / 180.0, az = 2.0 * M_PI * d.unit();
  w.sun.direction_W = Eigen::Vector3d(std::sin(tilt) * std::cos(az), std::sin(tilt) * std::sin(az), std::cos(tilt));
  w.lamps = base.lamps;
  const double lamp = d.uniform(ranges.lamp_intensity);
  for (auto& l : w.lamps) l.intensity *= lamp;
  w.marine_snow = base.marine_snow;
  w.marine_snow.density_per_m3 = d.uniform(ranges.marine_snow_per_m3);
  w.marine_snow.seed = d.u32();
  return w;
}

}  // namespace unav::sim

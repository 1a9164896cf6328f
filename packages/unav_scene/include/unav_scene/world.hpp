// World description (worlds/<name>/world.yaml) and the pipeline centre-line API.
// This header and its library (package unav_scene) need no OpenGL and no DDS:
// planning and evaluation use load_world() + nearest_pipe_point().
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "unav_scene/frames.hpp"
#include "unav_scene/water.hpp"

namespace unav::scene {

/// Segmentation class ids written to the segmentation image.
enum class SegClass : std::uint8_t { kWater = 0, kSeabed = 1, kPipeline = 2, kRock = 3, kOther = 4, kVehicle = 5 };

/// Every class's id and name (datasets' label tables): water, seabed, pipeline, rock, other, vehicle.
std::vector<std::pair<int, std::string>> seg_class_labels();

/// Surface appearance. `texture` is a procedural texture name: none, sand, rock, pipe_coating,
/// checker. Albedo multiplies the texture (linear RGB, 0..1).
struct Material {
  std::string texture = "none";
  Eigen::Vector3d albedo{0.5, 0.5, 0.5};
  double uv_scale_m = 1.0;  ///< metres per texture repeat
  /// Acoustic backscatter: Lambert's parameter mu [dB] (the surface returns mu cos^2(incidence)
  /// per unit area and solid angle). NaN = the class default (acoustic_reflectivity_db()).
  double acoustic_reflectivity_db = std::numeric_limits<double>::quiet_NaN();
  /// Physically based shading (metal/roughness, GGX). NaN = the texture's default
  /// (material_roughness()); 0.05..1, perceptual (alpha = roughness^2).
  double roughness = std::numeric_limits<double>::quiet_NaN();
  double metallic = 0.0;  ///< 0 dielectric (F0 of a 1.5-index surface in water), 1 metal (F0 = albedo)
  /// Relief of the texture's height field, peak to trough [m], shaded by bump mapping (sand
  /// ripples, rock cracks, growth on the coating). NaN = the texture's default (material_relief_m()).
  double relief_m = std::numeric_limits<double>::quiet_NaN();
  /// Settled sediment [0, 1]: the share of upward-facing surface (and of surface within 0.3 m of
  /// the mean seabed: burial) covered by sand. NaN = the default (material_sediment()): 0.5,
  /// none on the seabed itself.
  double sediment = std::numeric_limits<double>::quiet_NaN();
};

/// Roughness of `m`: its own, else by texture: sand 0.9, rock 0.8, pipe_coating 0.45 (a wet,
/// smooth polymer coat), none / checker 0.6.
double material_roughness(const Material& m);
/// Relief of `m` [m]: its own, else by texture (at its uv_scale_m): sand 0.02 (ripples of a
/// 2 m tile, wavelength 0.14 m), rock 0.03, pipe_coating 0.006, none / checker 0.
double material_relief_m(const Material& m);
/// Sediment cover of `m`: its own, else 0.5.
double material_sediment(const Material& m);
/// Same appearance (everything the renderer draws by): meshes that share it may be merged.
bool same_look(const Material& a, const Material& b);

/// Lambert mu [dB] of a class when its material gives none: seabed (sand) -27, pipeline (coated
/// steel) -12, rock -17, other -20 (APL-UW high-frequency handbook ranges: sand -25..-30 dB,
/// rock -15..-20 dB; hard man-made targets return well above the seabed).
double acoustic_reflectivity_db(SegClass seg_class);

struct Seabed {
  bool enabled = true;
  double depth_m = 10.0;                ///< mean depth of the seabed (NED z)
  Eigen::Vector2d center_ne{0.0, 0.0};  ///< centre of the patch (north, east) [m]
  Eigen::Vector2d size_m{60.0, 60.0};   ///< extent along north and east [m]
  double resolution_m = 0.5;            ///< grid spacing [m]
  /// A coarse flat seabed of this edge [m] is laid just below the detailed patch so the
  /// seabed fades into the water instead of ending at a visible edge (0 = none).
  double far_extent_m = 300.0;
  double relief_amplitude_m = 0.0;  ///< procedural relief (value-noise fBm) amplitude
  double relief_wavelength_m = 6.0;
  std::uint32_t relief_seed = 1;
  std::string heightmap_file;      ///< optional 8/16-bit grey PNG (absolute path)
  double heightmap_range_m = 1.0;  ///< white is this much shallower than black
  Material material{"sand", {0.76, 0.70, 0.55}, 2.0};

  /// Seabed depth (NED z, metres) at (north, east) from relief/heightmap (not the mesh).
  double depth_at(double n_m, double e_m) const;
  /// True when depth_at() is depth_m everywhere (no relief, no heightmap).
  bool is_flat() const { return !(relief_amplitude_m > 0.0) && hm_values.empty(); }
  // Heightmap samples (filled by load_world when heightmap_file is set), row-major, 0..1.
  int hm_width = 0, hm_height = 0;
  std::vector<float> hm_values;
};

/// A pipeline laid along a polyline; the renderer builds a tube with bends of bend_radius_m.
struct Pipeline {
  std::string name;
  std::vector<Eigen::Vector3d> points_W;  ///< polyline vertices, world NED [m]
  double radius_m = 0.25;
  double bend_radius_m = 1.0;  ///< centre-line radius of the bends at vertices
  Material material{"pipe_coating", {0.55, 0.42, 0.25}, 1.0};
  /// Centre line with the bends, sampled every <= 0.1 m (filled by load_world).
  std::vector<Eigen::Vector3d> centerline_W;
  /// Arc length at each centerline_W sample [m].
  std::vector<double> arc_length_m;
  double length_m() const { return arc_length_m.empty() ? 0.0 : arc_length_m.back(); }
};

/// Procedural rock: a noisy ellipsoid.
struct Rock {
  Eigen::Vector3d p_W{0, 0, 0};
  Eigen::Vector3d radii_m{0.3, 0.3, 0.2};
  double yaw_rad = 0.0;
  std::uint32_t seed = 1;
  Material material{"rock", {0.45, 0.42, 0.38}, 0.6};
};

/// A mesh file (assimp: OBJ, PLY, glTF/GLB, FBX, ...) or a primitive shape placed in the world.
struct Object {
  std::string name;
  std::string mesh_file;            ///< absolute path; empty for primitive shapes
  std::string shape;                ///< "box", "sphere", "plane" when mesh_file is empty
  Eigen::Vector3d size_m{1, 1, 1};  ///< box edges / plane x,y / sphere diameter
  Pose X_WO = Pose::Identity();
  Eigen::Vector3d scale{1, 1, 1};
  SegClass seg_class = SegClass::kOther;
  Material material{"none", {0.5, 0.5, 0.5}, 1.0};
  /// Moved while rendering (Renderer::set_object_pose: another vehicle of the fleet); X_WO is
  /// where it starts. Its texture is laid out in its own frame only for mesh UVs (a triplanar
  /// texture would slide over it: give it a plain material).
  bool movable = false;
};

struct Sun {
  Eigen::Vector3d direction_W{0.0, 0.0, 1.0};         ///< unit, direction the light travels (NED)
  Eigen::Vector3d surface_irradiance{1.0, 1.0, 1.0};  ///< E0 per channel (display units)
  double ambient_fraction = 0.35;                     ///< share of diffuse (sky + scattered) light
};

/// A lamp on the vehicle. Lamp frame L: x is the beam axis.
struct Lamp {
  std::string name;
  Pose X_BL = Pose::Identity();              ///< mount pose on base_link_frd
  double cone_half_angle_rad = 0.6;          ///< beam half angle (smooth falloff to zero at the edge)
  Eigen::Vector3d intensity{1.0, 1.0, 1.0};  ///< radiant intensity on the axis (units*m^2)
};

struct MarineSnow {
  double density_per_m3 = 0.0;  ///< particles per cubic metre around the camera
  double size_m = 0.004;        ///< particle diameter
  double box_m = 8.0;           ///< particles live in a box of this edge around the camera
  std::uint32_t seed = 7;
};

struct World {
  std::string name;
  std::string file;  ///< path of world.yaml
  std::string dir;   ///< its folder (relative paths resolve against it)
  WaterModel water;
  Seabed seabed;
  std::vector<Pipeline> pipelines;
  std::vector<Rock> rocks;
  std::vector<Object> objects;
  Sun sun;
  std::vector<Lamp> lamps;
  MarineSnow marine_snow;
  /// Water current model for the physics server (world.yaml `current: {file: ...}`, a
  /// config/water/currents YAML; absolute path); empty = still water.
  std::string current_file;
};

/// The seabed patch as a regular depth grid, for a consumer that interpolates bilinearly (the
/// physics server's contact, DVL and altimeter): depths_m[i][j] = seabed.depth_at(origin_n + i *
/// resolution_m, origin_e + j * resolution_m), rows running north. Nodes are the render mesh's
/// vertices when the patch size is a multiple of the resolution (both worlds shipped).
struct SeabedGrid {
  double origin_n = 0.0, origin_e = 0.0, resolution_m = 1.0;
  std::vector<std::vector<double>> depths_m;
};
SeabedGrid sample_seabed(const Seabed& seabed);

/// Load and validate worlds/<name>/world.yaml. Throws ConfigError naming the file and the key
/// (unknown key, wrong type, non-positive radius, missing mesh file, bad water preset ...).
World load_world(const std::string& path);

/// Fills pipe->centerline_W (bends of bend_radius_m at the vertices, sampled every <= step_m)
/// and pipe->arc_length_m from pipe->points_W: what load_world does for each pipeline.
void build_centerline(Pipeline* pipe, double step_m = 0.1);

/// A seeded scatter of rocks on the seabed (world.yaml `rock_field`): mostly small, a few large,
/// none closer than clearance_from_pipe_m to a pipeline. Same seed, same rocks.
struct RockField {
  int count = 0;
  std::uint32_t seed = 1;
  Eigen::Vector2d region_lo_ne{0, 0}, region_hi_ne{0, 0};  ///< [m]
  Eigen::Vector2d radius_m{0.1, 0.4};                      ///< min, max
  double clearance_from_pipe_m = 0.5;
  Material material{"rock", {0.45, 0.42, 0.38}, 0.6};
};
/// Appends the field's rocks to world->rocks (on world->seabed; after the pipelines are set).
void add_rock_field(World* world, const RockField& field);

/// Nearest point of any pipeline centre line (including bends) to a point.
struct PipeQuery {
  bool valid = false;        ///< false when the world has no pipeline
  std::size_t pipeline = 0;  ///< index into World::pipelines
  Eigen::Vector3d closest_W{0, 0, 0};
  double distance_m = 0;             ///< 3D distance to the centre line
  double horizontal_distance_m = 0;  ///< distance in the north-east plane (paper's e_p)
  double lateral_m = 0;              ///< signed horizontal offset, > 0 when the point is right of the pipe
  double heading_rad = 0;            ///< pipe heading at the nearest point, atan2(dE, dN), (-pi, pi]
  double arc_length_m = 0;           ///< arc length of the nearest point from the pipeline start
};

/// Query the nearest pipeline point. `horizontal` = true measures in the north-east plane
/// (ignores depth), as the pipe-following reward does.
PipeQuery nearest_pipe_point(const World& world, const Eigen::Vector3d& p_W, bool horizontal = true);

/// Horizontal distance [m] from p_W to the nearest pipeline centre line (+inf if none).
double distance_to_pipe(const World& world, const Eigen::Vector3d& p_W);

/// Heading [rad] of the pipe at the point nearest to p_W (0 if no pipeline).
double pipe_heading(const World& world, const Eigen::Vector3d& p_W);

/// Centre line of a polyline with circular bends of radius `bend_radius_m` at its vertices,
/// sampled every <= `step_m`.
std::vector<Eigen::Vector3d> bent_centerline(const std::vector<Eigen::Vector3d>& points_W, double bend_radius_m,
                                             double step_m = 0.1);

}  // namespace unav::scene

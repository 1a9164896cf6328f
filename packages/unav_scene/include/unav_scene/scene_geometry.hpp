// CPU geometry of a world: seabed grid, pipe tubes with bends, rocks, meshes loaded with
// assimp, primitive shapes. All vertices are in the world frame (NED, metres).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "unav_scene/world.hpp"

namespace unav::scene {

struct MeshData {
  std::vector<float> positions;        ///< xyz per vertex
  std::vector<float> normals;          ///< xyz per vertex (unit)
  std::vector<float> uvs;              ///< uv per vertex (metres / arc length based)
  std::vector<std::uint32_t> indices;  ///< triangles
  std::size_t vertex_count() const { return positions.size() / 3; }
  std::size_t triangle_count() const { return indices.size() / 3; }
  /// Apply a pose and per-axis scale (normals transformed with the inverse transpose).
  void transform(const Pose& X, const Eigen::Vector3d& scale = Eigen::Vector3d::Ones());
  void append(const MeshData& other);
};

/// A texture image of a mesh file (base colour, normal or occlusion-roughness-metallic map),
/// decoded: rgb8, rows bottom first (texture coordinate v = 0 is the image's bottom, as assimp
/// gives UVs). `source` names it in messages.
struct TextureImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::string source;
};

/// A mesh file material's own maps, drawn by the mesh's UVs (see MeshPart).
struct SurfaceMaps {
  /// Base colour (sRGB), times Material::albedo; null: the material's albedo alone.
  std::shared_ptr<const TextureImage> base_color;
  /// Tangent-space normal map (linear; x right = +u, y up = +v, z out of the surface: glTF's and
  /// OpenGL's convention); null: the geometric normal.
  std::shared_ptr<const TextureImage> normal;
  /// Occlusion (red), roughness (green), metallic (blue), linear: glTF's packing; separate grey
  /// maps are packed into one. Roughness and metallic are the map times the factors; null: none.
  std::shared_ptr<const TextureImage> orm;
  double roughness_factor = 1.0, metallic_factor = 1.0;  ///< the file's (glTF's default 1)
  bool any() const { return base_color || normal || orm; }
};

/// A part of a mesh that can be drawn coarser far away (a procedural rock): its triangles at
/// each level of detail as indices into the mesh's vertices, finest first (levels[0] is the part's
/// share of MeshData::indices), and how far each level's surface lies from the finest one's
/// vertices [m] (error_m[0] = 0; a renderer picks the coarsest level whose error stays under its
/// screen-space bound).
struct LodPart {
  std::vector<std::vector<std::uint32_t>> levels;
  std::vector<double> error_m;
};

/// The levels of detail of make_rock_mesh(seed, radii_m, subdivisions): the coarser icospheres'
/// triangles over the same vertices (each subdivision keeps its parent's vertices, in front), so a
/// coarse level's corners lie on the finest surface; `subdivisions` + 1 levels.
LodPart rock_lods(const MeshData& rock, int subdivisions);

struct SceneMesh {
  std::string name;
  MeshData mesh;
  SegClass seg_class = SegClass::kOther;
  Material material;
  bool triplanar = false;  ///< texture by world position (meshes without UVs: rocks, files)
  /// The mesh file's own maps (by its UVs); none: the material's procedural texture.
  SurfaceMaps maps;
  /// Parts drawn at levels of detail (rocks); empty: the mesh is drawn whole. When present,
  /// mesh.indices is their finest levels, in order.
  std::vector<LodPart> lod_parts;
  /// A movable object's mesh in the object's frame (its scale applied), as `mesh` is before its
  /// pose; empty for everything else.
  MeshData object_frame;
};

/// A mesh file's triangles grouped by their maps: one part per material with maps of its own
/// (glTF baseColorTexture, normalTexture, metallicRoughnessTexture and occlusionTexture; FBX/OBJ
/// diffuse, normal, roughness, metalness and ambient-occlusion maps; files next to the mesh or
/// embedded, e.g. GLB), and one part with every other triangle. Throws ConfigError naming the
/// mesh file and the texture when a texture is missing or cannot be decoded.
struct MeshPart {
  MeshData mesh;
  SurfaceMaps maps;
};
std::vector<MeshPart> load_mesh_parts(const std::string& path);

struct SceneGeometry {
  std::vector<SceneMesh> meshes;
  std::size_t triangle_count() const;
};

/// Build every mesh of the world. Mesh files are loaded here; a missing or unreadable file
/// throws ConfigError naming the file (and the world object).
SceneGeometry build_scene_geometry(const World& world);

/// A mesh of a movable object (Object::movable): its index in SceneGeometry::meshes and its
/// vertices and normals in the object's frame (the object's pose taken out, its scale kept), for
/// renderers that redraw it at another pose (MeshData::transform).
struct MovableMesh {
  std::size_t mesh = 0;
  MeshData local;
};
/// The movable objects' meshes of `geo` (built from `world`), by object name.
std::map<std::string, std::vector<MovableMesh>> movable_meshes(const World& world, const SceneGeometry& geo);

/// Load all meshes of a file with assimp (OBJ, PLY, glTF/GLB, FBX, ...), merged, triangulated,
/// with smooth normals. Throws ConfigError naming the file and assimp's reason.
MeshData load_mesh_file(const std::string& path);

/// Procedural rock: icosphere (subdivisions) displaced by seeded noise, radii per axis.
MeshData make_rock_mesh(std::uint32_t seed, const Eigen::Vector3d& radii_m, int subdivisions = 2);
MeshData make_box_mesh(const Eigen::Vector3d& size_m);
MeshData make_plane_mesh(double sx, double sy);  ///< sx x sy [m] in local xy, normal -z (up in NED)
MeshData make_sphere_mesh(double radius_m, int subdivisions = 3);
/// Whether the mesh bounds solids, and which way its triangles turn: +1 when every edge (vertices
/// welded by position) joins exactly two triangles that traverse it in opposite directions and
/// every connected part encloses a positive volume (counter-clockwise seen from outside: the
/// right-hand normal points out), -1 when every part's volume is negative (clockwise), 0 otherwise
/// (open, non-manifold, inconsistently wound or degenerate). Seen from outside, such a mesh's
/// faces turned away from the eye always lie behind faces turned towards it (back-face culling
/// changes no pixel).
int closed_orientation(const MeshData& m);
/// Tube of `radius_m` along a centre line (parallel-transport frames), uv = (arc/circumference),
/// closed by flat caps, counter-clockwise seen from outside.
MeshData make_tube_mesh(const std::vector<Eigen::Vector3d>& centerline_W, double radius_m, int sides = 16);
MeshData make_seabed_mesh(const Seabed& sb);

/// Write a mesh as Wavefront OBJ (v, vn, f). Throws ConfigError when the file cannot be written.
void write_obj(const MeshData& mesh, const std::string& path);

}  // namespace unav::scene

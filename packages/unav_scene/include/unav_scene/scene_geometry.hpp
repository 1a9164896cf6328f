// CPU geometry of a world: seabed grid, pipe tubes with bends, rocks, meshes loaded with
// assimp, primitive shapes. All vertices are in the world frame (NED, metres).
#pragma once

#include <cstdint>
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

/// A texture image of a mesh file (its base colour), decoded: rgb8, rows bottom first (texture
/// coordinate v = 0 is the image's bottom, as assimp gives UVs). `source` names it in messages.
struct TextureImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::string source;
};

struct SceneMesh {
  std::string name;
  MeshData mesh;
  SegClass seg_class = SegClass::kOther;
  Material material;
  bool triplanar = false;  ///< texture by world position (meshes without UVs: rocks, files)
  /// The mesh file's own base-colour texture (by its UVs, times material.albedo); null: the
  /// material's procedural texture.
  std::shared_ptr<const TextureImage> base_color;
};

/// A mesh file's triangles grouped by their base-colour texture: one part per textured material
/// (glTF baseColorTexture, FBX/OBJ diffuse map; files next to the mesh or embedded, e.g. GLB),
/// and one part with every untextured triangle. Throws ConfigError naming the mesh file and the
/// texture when a texture is missing or cannot be decoded.
struct MeshPart {
  MeshData mesh;
  std::shared_ptr<const TextureImage> base_color;
};
std::vector<MeshPart> load_mesh_parts(const std::string& path);

struct SceneGeometry {
  std::vector<SceneMesh> meshes;
  std::size_t triangle_count() const;
};

/// Build every mesh of the world. Mesh files are loaded here; a missing or unreadable file
/// throws ConfigError naming the file (and the world object).
SceneGeometry build_scene_geometry(const World& world);

/// Load all meshes of a file with assimp (OBJ, PLY, glTF/GLB, FBX, ...), merged, triangulated,
/// with smooth normals. Throws ConfigError naming the file and assimp's reason.
MeshData load_mesh_file(const std::string& path);

/// Procedural rock: icosphere (subdivisions) displaced by seeded noise, radii per axis.
MeshData make_rock_mesh(std::uint32_t seed, const Eigen::Vector3d& radii_m, int subdivisions = 2);
MeshData make_box_mesh(const Eigen::Vector3d& size_m);
MeshData make_plane_mesh(double sx, double sy);  ///< sx x sy [m] in local xy, normal -z (up in NED)
MeshData make_sphere_mesh(double radius_m, int subdivisions = 3);
/// Tube of `radius_m` along a centre line (parallel-transport frames), uv = (arc/circumference).
MeshData make_tube_mesh(const std::vector<Eigen::Vector3d>& centerline_W, double radius_m, int sides = 16);
MeshData make_seabed_mesh(const Seabed& sb);

/// Write a mesh as Wavefront OBJ (v, vn, f). Throws ConfigError when the file cannot be written.
void write_obj(const MeshData& mesh, const std::string& path);

}  // namespace unav::scene

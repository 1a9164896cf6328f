// World loading, pipeline centre-line API, scene geometry and mesh files (no OpenGL).
#include <gtest/gtest.h>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "unav_scene/errors.hpp"
#include "unav_scene/pipe_tracking.hpp"
#include "unav_scene/scene_geometry.hpp"
#include "unav_scene/world.hpp"

using namespace unav::scene;
namespace fs = std::filesystem;

namespace {

const std::string kRoot = UNAV_REPO_ROOT;

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("unav_scene_test_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string write_file(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p.string();
}

// Expect a ConfigError whose message contains every fragment.
template <typename F>
void expect_config_error(F&& f, std::initializer_list<std::string> fragments) {
  try {
    f();
    ADD_FAILURE() << "no ConfigError thrown";
  } catch (const ConfigError& e) {
    for (const auto& frag : fragments)
      EXPECT_NE(std::string(e.what()).find(frag), std::string::npos)
          << "message: " << e.what() << "\nmissing: " << frag;
  }
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

TEST(World, PipeInspectionHasTwentyMetrePipeWithLeftThenRightTurn) {
  const World w = load_world(kRoot + "/worlds/pipe_inspection/world.yaml");
  ASSERT_EQ(w.pipelines.size(), 1u);
  const Pipeline& p = w.pipelines[0];
  EXPECT_GT(p.length_m(), 18.0);
  EXPECT_LT(p.length_m(), 24.0);
  EXPECT_NEAR(w.seabed.depth_m, 10.0, 1e-9);
  for (const auto& v : p.points_W) EXPECT_NEAR(v.z(), 10.0 - 0.25 * 0.6, 0.2);  // on the seabed
  // Heading changes at the vertices: NED heading atan2(east, north); a left turn decreases it.
  std::vector<double> turns;
  for (std::size_t i = 1; i + 1 < p.points_W.size(); ++i) {
    const Eigen::Vector3d a = p.points_W[i] - p.points_W[i - 1], b = p.points_W[i + 1] - p.points_W[i];
    turns.push_back(wrap(std::atan2(b.y(), b.x()) - std::atan2(a.y(), a.x())));
  }
  ASSERT_EQ(turns.size(), 2u);
  EXPECT_LT(turns[0], -0.5);  // left
  EXPECT_GT(turns[1], 0.5);   // right
  EXPECT_GE(w.rocks.size(), 20u);
  EXPECT_EQ(w.lamps.size(), 2u);
  EXPECT_EQ(w.water.name, "jerlov_IB");
}

TEST(World, LoopVariantEndsNearItsStart) {
  const World w = load_world(kRoot + "/worlds/pipe_inspection_loop/world.yaml");
  ASSERT_EQ(w.pipelines.size(), 1u);
  const auto& c = w.pipelines[0].centerline_W;
  EXPECT_LT((c.front() - c.back()).head<2>().norm(), 2.5);
  EXPECT_GT(w.pipelines[0].length_m(), 30.0);
}

TEST(World, NearestPipePointDistanceHeadingAndSide) {
  const World w = load_world(kRoot + "/worlds/pipe_inspection/world.yaml");
  // First leg runs north along east = 0 from north 0 to 7 (bend starts 7 - 1.5 tan(22.5 deg)).
  const PipeQuery q = nearest_pipe_point(w, {3.0, 1.0, 8.0});
  ASSERT_TRUE(q.valid);
  EXPECT_NEAR(q.horizontal_distance_m, 1.0, 1e-9);
  EXPECT_NEAR(q.heading_rad, 0.0, 1e-9);
  EXPECT_NEAR(q.lateral_m, 1.0, 1e-9);     // east of a north-going pipe = right
  EXPECT_NEAR(q.arc_length_m, 3.0, 1e-3);  // the leg slopes a few mm with the seabed relief
  EXPECT_NEAR(distance_to_pipe(w, {3.0, -0.4, 9.0}), 0.4, 1e-9);
  EXPECT_NEAR(nearest_pipe_point(w, {3.0, -0.4, 9.0}).lateral_m, -0.4, 1e-9);
  // Middle leg heads north-west (-45 deg).
  EXPECT_NEAR(pipe_heading(w, {9.0, -2.0, 9.0}), -M_PI / 4, 1e-6);
  // Last leg heads north again.
  EXPECT_NEAR(pipe_heading(w, {16.0, -4.5, 9.0}), 0.0, 1e-6);
  // Inside the first bend the heading lies between the legs' headings.
  const double h = pipe_heading(w, {7.0, -0.3, 9.0});
  EXPECT_LT(h, 0.0);
  EXPECT_GT(h, -M_PI / 4);
}

TEST(World, BentCenterlineKeepsBendRadius) {
  // 90 deg corner with a 2 m bend: the arc midpoint lies R (sqrt2 - 1) from the corner.
  const auto c = bent_centerline({{0, 0, 0}, {10, 0, 0}, {10, 10, 0}}, 2.0, 0.01);
  double dmin = 1e9;
  for (const auto& p : c) dmin = std::min(dmin, (p - Eigen::Vector3d(10, 0, 0)).norm());
  EXPECT_NEAR(dmin, 2.0 * (std::sqrt(2.0) - 1.0), 1e-3);  // sampling 1 cm -> < 1 mm error
  for (std::size_t i = 1; i < c.size(); ++i) EXPECT_LE((c[i] - c[i - 1]).norm(), 0.0101);
}

TEST(WorldErrors, UnknownKeyNamesFileAndKey) {
  const auto d = temp_dir("unknown_key");
  const auto f = write_file(d / "world.yaml", "name: x\nseabed: {depth_m: 10, colour: red}\n");
  expect_config_error([&] { load_world(f); }, {f, "seabed.colour", "unknown key"});
  const auto g = write_file(d / "world2.yaml", "name: x\nsea_bed: {}\n");
  expect_config_error([&] { load_world(g); }, {g, "sea_bed"});
}

TEST(WorldErrors, MissingMeshNamesFileAndKey) {
  const auto d = temp_dir("missing_mesh");
  const auto f = write_file(d / "world.yaml", "objects:\n  - {name: wreck, mesh: meshes/wreck.glb}\n");
  expect_config_error([&] { load_world(f); }, {f, "objects[0].mesh", (d / "meshes/wreck.glb").string()});
}

TEST(WorldErrors, UnreadableMeshNamesFile) {
  const auto d = temp_dir("bad_mesh");
  write_file(d / "junk.obj", "this is not a mesh\n\x01\x02\x03");
  const auto f = write_file(d / "world.yaml", "objects:\n  - {name: junk, mesh: junk.obj}\n");
  const World w = load_world(f);
  expect_config_error([&] { build_scene_geometry(w); }, {f, "junk", (d / "junk.obj").string()});
}

TEST(WorldErrors, BadValuesNameTheKey) {
  const auto d = temp_dir("bad_values");
  expect_config_error(
      [&] { load_world(write_file(d / "a.yaml", "pipelines:\n  - {radius_m: -1, points_ne: [[0,0],[1,0]]}\n")); },
      {"pipelines[0].radius_m"});
  expect_config_error([&] { load_world(write_file(d / "b.yaml", "water: {preset: jerlov_XII}\n")); },
                      {"water.preset", "jerlov_XII", "jerlov_II"});
  expect_config_error([&] { load_world(write_file(d / "c.yaml", "lights: {sun: {direction_ned: [0, 0, -1]}}\n")); },
                      {"lights.sun.direction_ned"});
  expect_config_error([&] { load_world(write_file(d / "d.yaml", "pipelines:\n  - {points_ne: [[0,0]]}\n")); },
                      {"pipelines[0].points_ne"});
  expect_config_error([&] { load_world((d / "does_not_exist.yaml").string()); },
                      {"does_not_exist.yaml", "cannot open"});
  expect_config_error([&] { load_world(write_file(d / "e.yaml", "seabed: {material: {texture: marble}}\n")); },
                      {"seabed.material.texture", "marble"});
}

// Physically based material keys: each out-of-range value names its key and rule; defaults come
// from the texture (sand rough and rippled, the pipe coating smooth, an untextured object flat).
TEST(WorldErrors, MaterialKeysAreCheckedAndDefaultByTexture) {
  const auto d = temp_dir("material_keys");
  const auto bad = [&](const std::string& name, const std::string& material) {
    return write_file(d / name, "seabed: {material: " + material + "}\n");
  };
  std::string f = bad("r.yaml", "{texture: sand, roughness: 0}");
  expect_config_error([&] { load_world(f); }, {f, "seabed.material.roughness", "[0.05, 1]"});
  f = bad("m.yaml", "{texture: sand, metallic: 1.5}");
  expect_config_error([&] { load_world(f); }, {f, "seabed.material.metallic", "[0, 1]"});
  f = bad("h.yaml", "{texture: sand, uv_scale_m: 0.1, relief_m: 0.2}");
  expect_config_error([&] { load_world(f); }, {f, "seabed.material.relief_m", "uv_scale_m / 2"});
  f = bad("s.yaml", "{texture: rock, sediment: .nan}");
  expect_config_error([&] { load_world(f); }, {f, "seabed.material.sediment"});
  const World w = load_world(write_file(d / "ok.yaml", "seabed: {material: {texture: sand, metallic: 0.25}}\n"));
  EXPECT_DOUBLE_EQ(material_roughness(w.seabed.material), 0.9);
  EXPECT_DOUBLE_EQ(material_relief_m(w.seabed.material), 0.02);
  EXPECT_DOUBLE_EQ(w.seabed.material.metallic, 0.25);
  Material coat{"pipe_coating", {1, 1, 1}, 3.0};
  EXPECT_DOUBLE_EQ(material_roughness(coat), 0.45);
  coat.roughness = 0.2;
  EXPECT_DOUBLE_EQ(material_roughness(coat), 0.2);
  EXPECT_DOUBLE_EQ(material_relief_m(Material{}), 0.0);
  EXPECT_DOUBLE_EQ(material_sediment(Material{}), 0.5);
  EXPECT_FALSE(same_look(coat, Material{"pipe_coating", {1, 1, 1}, 3.0}));
}

// The seabed as a depth grid on the render mesh's nodes (what the physics server interpolates).
TEST(World, SeabedGridSamplesTheReliefOnTheMeshNodes) {
  const World w = load_world(kRoot + "/worlds/pipe_inspection/world.yaml");
  ASSERT_FALSE(w.seabed.is_flat());
  const SeabedGrid g = sample_seabed(w.seabed);
  // 64 m at 1 m: 65 x 65 nodes from (10 - 32, -2 - 32).
  ASSERT_EQ(g.depths_m.size(), 65u);
  ASSERT_EQ(g.depths_m[0].size(), 65u);
  EXPECT_DOUBLE_EQ(g.origin_n, -22.0);
  EXPECT_DOUBLE_EQ(g.origin_e, -34.0);
  const MeshData mesh = make_seabed_mesh(w.seabed);
  ASSERT_EQ(mesh.positions.size(), 3u * 65u * 65u);
  double max_err = 0.0;
  for (std::size_t i = 0; i < 65; ++i)
    for (std::size_t j = 0; j < 65; ++j) {
      const std::size_t v = 3 * (i * 65 + j);
      EXPECT_NEAR(mesh.positions[v], g.origin_n + static_cast<double>(i), 1e-5);
      EXPECT_NEAR(mesh.positions[v + 1], g.origin_e + static_cast<double>(j), 1e-5);
      max_err = std::max(max_err, std::abs(mesh.positions[v + 2] - g.depths_m[i][j]));
    }
  EXPECT_LT(max_err, 1e-5) << "grid depths must be the mesh vertices' (float positions)";
  // A flat seabed is flat; a 0.7 m resolution over 2 m covers the patch with a 4th node.
  Seabed flat;
  flat.size_m = {2.0, 2.0};
  flat.resolution_m = 0.7;
  EXPECT_TRUE(flat.is_flat());
  const SeabedGrid fg = sample_seabed(flat);
  EXPECT_EQ(fg.depths_m.size(), 4u);
  EXPECT_DOUBLE_EQ(fg.depths_m[3][3], flat.depth_m);
}

TEST(World, CurrentFileIsResolvedAndChecked) {
  const auto d = temp_dir("current");
  write_file(d / "still.yaml", "current: {type: constant, velocity: [0, 0, 0]}\n");
  const World w = load_world(write_file(d / "world.yaml", "current: {file: still.yaml}\n"));
  EXPECT_EQ(w.current_file, (d / "still.yaml").string());
  expect_config_error([&] { load_world(write_file(d / "b.yaml", "current: {file: nowhere.yaml}\n")); },
                      {"current.file", (d / "nowhere.yaml").string()});
  expect_config_error([&] { load_world(write_file(d / "c.yaml", "current: {velocity: [1, 0, 0]}\n")); },
                      {"current.velocity", "unknown key"});
  EXPECT_TRUE(load_world(kRoot + "/worlds/pipe_inspection/world.yaml").current_file.empty());
}

TEST(Meshes, AssimpLoadsObjPlyGltfGlbFbx) {
  // The repository's boulder (OBJ, written by unav_make_rock) re-exported by assimp into the
  // other formats; each must load back with the same triangle count.
  const std::string obj = kRoot + "/worlds/pipe_inspection/meshes/boulder.obj";
  const MeshData ref = load_mesh_file(obj);
  ASSERT_GT(ref.triangle_count(), 100u);
  Assimp::Importer imp;
  const aiScene* scene = imp.ReadFile(obj, aiProcess_Triangulate);
  ASSERT_NE(scene, nullptr);
  const auto d = temp_dir("formats");
  Assimp::Exporter exp;
  const std::pair<const char*, const char*> formats[] = {
      {"ply", "boulder.ply"}, {"gltf2", "boulder.gltf"}, {"glb2", "boulder.glb"}, {"fbxa", "boulder.fbx"}};
  for (const auto& [id, name] : formats) {
    const std::string path = (d / name).string();
    ASSERT_EQ(exp.Export(scene, id, path), AI_SUCCESS) << id << ": " << exp.GetErrorString();
    const MeshData m = load_mesh_file(path);
    EXPECT_EQ(m.triangle_count(), ref.triangle_count()) << name;
    ASSERT_EQ(m.normals.size(), m.positions.size()) << name;
  }
}

TEST(Meshes, TubeHasRingsOnlyWhereItsCentreLineTurns) {
  // A straight run sampled every 0.1 m is one prism (2 rings: 16 sides x 2 triangles, plus two
  // 16-triangle caps); the far ring's uv is the run's length. A right-angle kink at sample 5 keeps
  // the rings where the tangent changes (samples 4, 5, 6) and the ends: 5 rings, 4 segments.
  std::vector<Eigen::Vector3d> straight, kinked;
  for (int i = 0; i <= 10; ++i) straight.emplace_back(0.1 * i, 0.0, 10.0);
  const MeshData s = make_tube_mesh(straight, 0.25, 16);
  EXPECT_EQ(s.triangle_count(), 2u * 16u + 2u * 16u);
  constexpr std::size_t kSecondRing = 17;          // 16 sides + the seam's copy
  EXPECT_NEAR(s.uvs[2 * kSecondRing], 1.0, 1e-6);  // its first vertex: arc length 1 m
  EXPECT_NEAR(s.positions[3 * kSecondRing], 1.0, 1e-6);
  for (int i = 0; i <= 10; ++i) kinked.emplace_back(i <= 5 ? 0.1 * i : 0.5, i <= 5 ? 0.0 : 0.1 * (i - 5), 10.0);
  const MeshData k = make_tube_mesh(kinked, 0.25, 16);
  EXPECT_EQ(k.triangle_count(), 4u * 2u * 16u + 2u * 16u);
}

TEST(Meshes, ClosedOrientationOfTheGenerators) {
  // Solids, counter-clockwise seen from outside (+1); reversing every triangle gives -1; a mesh
  // with a hole, a plane and a mix of both orientations give 0.
  std::vector<Eigen::Vector3d> bent;
  for (int i = 0; i <= 20; ++i) bent.emplace_back(0.1 * i, i > 10 ? 0.1 * (i - 10) : 0.0, 10.0);
  const MeshData solids[] = {make_tube_mesh(bent, 0.25, 16), make_rock_mesh(3, {0.4, 0.3, 0.2}, 2),
                             make_rock_mesh(4, {0.1, 0.1, 0.1}, 1), make_box_mesh({0.6, 0.35, 0.3}),
                             make_sphere_mesh(0.5, 2)};
  for (const MeshData& m : solids) {
    EXPECT_EQ(closed_orientation(m), 1) << m.triangle_count() << " triangles";
    MeshData r = m;
    for (std::size_t t = 0; t < r.triangle_count(); ++t) std::swap(r.indices[3 * t + 1], r.indices[3 * t + 2]);
    EXPECT_EQ(closed_orientation(r), -1);
    MeshData holed = m;
    holed.indices.resize(holed.indices.size() - 3);
    EXPECT_EQ(closed_orientation(holed), 0);
    MeshData mixed = m;
    mixed.append(r);  // two parts turned opposite ways (and overlapping: still closed each)
    EXPECT_EQ(closed_orientation(mixed), 0);
  }
  EXPECT_EQ(closed_orientation(make_plane_mesh(2.0, 2.0)), 0);
  // Two separate solids turned the same way: one closed mesh (a rock group).
  MeshData two = solids[1], far = solids[2];
  far.transform(pose_from_xyz_rpy({5.0, 0.0, 0.0}, {0.0, 0.0, 0.0}));
  two.append(far);
  EXPECT_EQ(closed_orientation(two), 1);
}

TEST(Meshes, RockLevelsOfDetail) {
  // A unit icosphere (no noise): the coarse levels are the 80- and 20-face icospheres over its
  // first 42 and 12 vertices. Their error is bounded by the sag of the icosahedron's faces,
  // 1 - (distance of a face's plane from the centre) = 1 - 0.794654 (circumradius 1), and at least
  // the sag over an icosahedron edge that a finer vertex (the edge's midpoint, pushed out to the
  // sphere) lies over: 1 - cos(theta / 2) with cos(theta) = 1 / sqrt(5), 0.149349.
  const MeshData sphere = make_sphere_mesh(1.0, 2);
  const LodPart s = rock_lods(sphere, 2);
  ASSERT_EQ(s.levels.size(), 3u);
  ASSERT_EQ(s.error_m.size(), 3u);
  EXPECT_EQ(s.levels[0], sphere.indices);
  EXPECT_EQ(s.levels[1].size(), 3u * 80u);
  EXPECT_EQ(s.levels[2].size(), 3u * 20u);
  for (std::uint32_t i : s.levels[1]) EXPECT_LT(i, 42u);
  for (std::uint32_t i : s.levels[2]) EXPECT_LT(i, 12u);
  EXPECT_EQ(s.error_m[0], 0.0);
  EXPECT_GE(s.error_m[2], 1.0 - std::sqrt((1.0 + 1.0 / std::sqrt(5.0)) / 2.0) - 1e-9);
  EXPECT_LE(s.error_m[2], 1.0 - 0.794654);
  EXPECT_GT(s.error_m[1], 0.0);
  EXPECT_LT(s.error_m[1], 0.5 * s.error_m[2]);  // half the edge length: about a quarter of the sag
  // A rock: the same triangle counts, and its errors scale with its size (same seed, same shape).
  const LodPart r1 = rock_lods(make_rock_mesh(9, {0.4, 0.3, 0.2}, 2), 2);
  const LodPart r2 = rock_lods(make_rock_mesh(9, {0.8, 0.6, 0.4}, 2), 2);
  ASSERT_EQ(r1.levels.size(), 3u);
  EXPECT_EQ(r1.levels[0].size(), 3u * 320u);
  for (std::size_t k = 1; k < 3; ++k) {
    EXPECT_GT(r1.error_m[k], r1.error_m[k - 1]);
    EXPECT_NEAR(r2.error_m[k], 2.0 * r1.error_m[k], 1e-6);
  }
  EXPECT_THROW(rock_lods(make_rock_mesh(9, {0.4, 0.3, 0.2}, 1), 2), std::invalid_argument);
}

TEST(Meshes, SceneGeometryOfPipeInspection) {
  const World w = load_world(kRoot + "/worlds/pipe_inspection/world.yaml");
  const SceneGeometry g = build_scene_geometry(w);
  bool seabed = false, pipe = false, rock = false, other = false;
  for (const auto& m : g.meshes) {
    seabed |= m.seg_class == SegClass::kSeabed;
    pipe |= m.seg_class == SegClass::kPipeline;
    rock |= m.seg_class == SegClass::kRock;
    other |= m.seg_class == SegClass::kOther;
    EXPECT_EQ(m.mesh.normals.size(), m.mesh.positions.size()) << m.name;
    EXPECT_EQ(m.mesh.uvs.size() / 2, m.mesh.positions.size() / 3) << m.name;
    // Rocks come with levels of detail, one part a rock; their finest levels are the mesh.
    EXPECT_EQ(m.seg_class == SegClass::kRock && m.name == "rocks", !m.lod_parts.empty()) << m.name;
    std::vector<std::uint32_t> finest;
    for (const LodPart& p : m.lod_parts) finest.insert(finest.end(), p.levels[0].begin(), p.levels[0].end());
    if (!m.lod_parts.empty()) {
      EXPECT_EQ(finest, m.mesh.indices) << m.name;
    }
  }
  EXPECT_TRUE(seabed && pipe && rock && other);
  // Every tube vertex lies one radius from the bent centre line (bends included).
  for (const auto& m : g.meshes) {
    if (m.seg_class != SegClass::kPipeline) continue;
    const auto& c = w.pipelines[0].centerline_W;
    for (std::size_t i = 0; i < m.mesh.vertex_count(); i += 97) {
      const Eigen::Vector3d p(m.mesh.positions[3 * i], m.mesh.positions[3 * i + 1], m.mesh.positions[3 * i + 2]);
      double dmin = 1e9;
      for (std::size_t k = 0; k + 1 < c.size(); ++k) {
        const Eigen::Vector3d ab = c[k + 1] - c[k];
        const double t = std::clamp((p - c[k]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        dmin = std::min(dmin, (p - c[k] - t * ab).norm());
      }
      EXPECT_LE(dmin, 0.25 + 1e-4);  // caps lie inside
    }
  }
}

// Cross-track figures on the straight first run of the pipe_inspection pipe (north along
// east = 0 from north = 0): a track 0.3 m east of it has e_p = 0.3 everywhere; a track that
// leaves it sideways is lost at the first point beyond 2.5 m and counts up to it.
TEST(PipeTracking, CrossTrackErrorAndFollowedLength) {
  const unav::scene::World w =
      unav::scene::load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  std::vector<Eigen::Vector3d> along;
  for (int i = 0; i <= 50; ++i) along.emplace_back(0.1 * i, 0.3, 8.0);
  const auto t = unav::scene::track_pipe(w, along);
  EXPECT_NEAR(t.mean_e_p_m, 0.3, 1e-6);
  EXPECT_NEAR(t.max_e_p_m, 0.3, 1e-6);
  EXPECT_NEAR(t.followed_m, 5.0, 0.02);  // centre line sampled every <= 0.1 m
  EXPECT_FALSE(t.lost);
  EXPECT_NEAR(t.followed_fraction, 5.0 / t.pipe_length_m, 1e-3);
  std::vector<Eigen::Vector3d> away{
      {1.0, 0.0, 8.0}, {2.0, 1.0, 8.0}, {3.0, 2.0, 8.0}, {4.0, 3.0, 8.0}, {5.0, 0.0, 8.0}};
  const auto l = unav::scene::track_pipe(w, away);
  EXPECT_TRUE(l.lost);
  EXPECT_EQ(l.lost_at_index, 3);
  EXPECT_EQ(l.samples, 4);
  EXPECT_NEAR(l.followed_m, 3.0, 0.02);  // the point at north 5 after the loss does not count
  EXPECT_NEAR(l.max_e_p_m, 3.0, 1e-6);
  EXPECT_FALSE(l.completed);
  // Along the whole pipe and beyond its end: counting stops 1 m before the end (completed).
  std::vector<Eigen::Vector3d> all;
  for (const auto& c : w.pipelines[0].centerline_W) all.push_back(c);
  for (int i = 1; i <= 40; ++i) all.push_back(w.pipelines[0].centerline_W.back() + Eigen::Vector3d(0.1 * i, 0, 0));
  const auto c = unav::scene::track_pipe(w, all);
  EXPECT_TRUE(c.completed);
  EXPECT_FALSE(c.lost);
  EXPECT_NEAR(c.mean_e_p_m, 0.0, 1e-9);
  EXPECT_GT(c.followed_fraction, (c.pipe_length_m - 1.1) / c.pipe_length_m);
}

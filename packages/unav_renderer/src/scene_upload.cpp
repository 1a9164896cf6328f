// The world on the GPU: meshes (chunks, levels of detail), surface textures, marine snow seeds,
// the shadow casters' boxes and the sun-free terrain (shadow culling); the context self-test.
#include "renderer_impl.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "shaders.hpp"
#include "textures.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_scene/noise.hpp"

namespace unav::renderer {

void Renderer::Impl::self_test() {
  // Throwaway tiny frame: catches a context that renders nothing (no silent black images),
  // and avoids llvmpipe's "first framebuffer stays slow" oddity (TOOLCHAIN.md).
  Program p(detail::kPostVS, detail::kConstFS, "self-test");
  GLuint tex = make_tex(GL_RGBA8, 8, 8, GL_RGBA, GL_UNSIGNED_BYTE, GL_NEAREST);
  GLuint fbo = gl::make_fbo({tex}, 0, "self-test");
  glViewport(0, 0, 8, 8);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT);
  p.use();
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::uint8_t px[8 * 8 * 4] = {};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, 8, 8, GL_RGBA, GL_UNSIGNED_BYTE, px);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(1, &fbo);
  glDeleteTextures(1, &tex);
  glDeleteProgram(p.id());
  constexpr std::size_t kPx = std::size_t{4} * 27;  // pixel (3, 3) of the 8x8 test frame
  const int r = px[kPx], g = px[kPx + 1], b = px[kPx + 2];
  if (std::abs(r - 64) > 2 || std::abs(g - 128) > 2 || std::abs(b - 191) > 2)
    throw GlError("OpenGL context on '" + ctx->gl_renderer() + "' (" + ctx->platform() +
                  ") renders nothing usable: read back (" + std::to_string(r) + ", " + std::to_string(g) + ", " +
                  std::to_string(b) + ") instead of (64, 128, 191)");
}

const Renderer::Impl::SurfaceMaps& Renderer::Impl::texture(const std::string& name) {
  auto it = textures.find(name);
  if (it != textures.end()) return it->second;
  const int size = name == "none" ? 1 : std::max(16, options.texture_size);
  const auto tex = detail::make_texture(name, size);
  SurfaceMaps& maps = textures[name];
  // Albedo in sRGB, the relief height (alpha) linear; its slope mipmapped: a footprint's mean.
  maps.colour = gl::make_tiled_tex(GL_SRGB8_ALPHA8, size, size, GL_RGBA, GL_UNSIGNED_BYTE, tex.rgba.data());
  maps.slope = gl::make_tiled_tex(GL_RG16F, size, size, GL_RG, GL_FLOAT, tex.gradient.data());
  return maps;
}

// Alpha reads 1 (a relief is never drawn from a mesh file's map: GpuMesh::bump is off).
// A mesh file's map as a mipmapped, repeating texture: sRGB (base colour) or linear (normal, ORM).
GLuint Renderer::Impl::image_texture(const std::shared_ptr<const TextureImage>& image, bool srgb) {
  const std::pair<const TextureImage*, bool> key{image.get(), srgb};
  auto it = image_textures.find(key);
  if (it != image_textures.end()) return it->second;
  mesh_images.push_back(image);
  return image_textures[key] = gl::make_tiled_tex(srgb ? GL_SRGB8 : GL_RGB8, image->width, image->height, GL_RGB,
                                                  GL_UNSIGNED_BYTE, image->rgb.data());
}

void Renderer::Impl::upload_scene(const SceneGeometry& geo) {
  triangles = geo.triangle_count();
  movable.clear();
  mesh_movable.assign(geo.meshes.size(), false);
  std::map<std::size_t, std::pair<std::string, MeshData>> movable_local;  // by mesh: object name, local mesh
  for (auto& [name, parts] : movable_meshes(world, geo))
    for (MovableMesh& m : parts) movable_local[m.mesh] = {name, std::move(m.local)};
  {  // Sediment is the seabed's own sand: its texture's mean (linear) times its albedo.
    const auto px = detail::make_texture(world.seabed.material.texture, 64).rgba;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    const std::size_t n = px.size() / 4;
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) {
        const double e = px[i * 4 + c] / 255.0;
        sum[c] += e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
      }
    sediment_albedo = (sum / static_cast<double>(n)).cwiseProduct(world.seabed.material.albedo);
  }
  for (const auto& sm : geo.meshes) {
    GpuMesh g;
    g.seg_class = sm.seg_class;
    g.material = sm.material;
    g.triplanar = sm.triplanar;
    g.winding = closed_orientation(sm.mesh);
    g.terrain = sm.name == "seabed" || sm.name == "seabed_far";
    if (g.terrain) g.tan_slope = steepest_slope(sm.mesh);
    g.macro = g.terrain && sm.material.texture != "none";
    g.sections = sm.material.texture == "pipe_coating" && !sm.triplanar;
    g.texture = texture(sm.material.texture).colour;
    g.roughness = static_cast<float>(material_roughness(sm.material));
    g.metallic = static_cast<float>(sm.material.metallic);
    g.relief_m = static_cast<float>(material_relief_m(sm.material));
    g.bump = g.relief_m > 0.0f && sm.material.texture != "none";
    if (sm.maps.any()) {  // the mesh file's own maps, by its UVs (one repeat per unit)
      g.texture = sm.maps.base_color ? image_texture(sm.maps.base_color, true) : texture("none").colour;
      g.material.uv_scale_m = 1.0;
      g.macro = g.sections = false;
      g.bump = false;  // the file's normal map, if any, instead of the procedural relief
      if (sm.maps.normal) g.normal_map = image_texture(sm.maps.normal, false);
      if (sm.maps.orm) {
        // The map times the factors: the world's roughness / metallic when it sets them, else the file's.
        g.orm_map = image_texture(sm.maps.orm, false);
        g.roughness =
            static_cast<float>(std::isnan(sm.material.roughness) ? sm.maps.roughness_factor : sm.material.roughness);
        g.metallic = static_cast<float>(sm.material.metallic > 0.0 ? sm.material.metallic : sm.maps.metallic_factor);
      }
    }
    if (g.bump) g.gradient = texture(sm.material.texture).slope;
    // A dielectric's highlight in water is faint (F0 = 0.0032 for index 1.5 against 1.34): only
    // smooth ones show it (roughness 0.45: +4..30 % over the diffuse at the peak; 0.8: < 1 %). An
    // ORM map varies both per pixel.
    g.specular = g.metallic > 0.0f || g.roughness < 0.7f || g.orm_map != 0;
    g.sediment_cover = static_cast<float>(material_sediment(sm.material));
    g.sediment = !g.macro && sm.seg_class != SegClass::kSeabed && g.sediment_cover > 0.0f;
    // A height field on a grid is drawn by tiles at levels of detail (the skirts' points appended
    // to a copy of its mesh); any other mesh in chunks.
    MeshData lod_mesh;
    const MeshData* mesh = &sm.mesh;
    std::vector<float> drop;
    std::vector<std::uint32_t> indices;
    int rows = 0, cols = 0;
    if (g.terrain && grid_layout(sm.mesh, &rows, &cols)) {
      lod_mesh = sm.mesh;
      indices = terrain_lod(&lod_mesh, rows, cols, &drop, &g.chunks, &g.tiles, &g.tile_cols, &g.lift);
      g.lamp_lift = g.lift;
      mesh = &lod_mesh;
    } else if (!sm.lod_parts.empty()) {
      indices = lod_indices(sm, &g.chunks, &g.lod, &g.lift);
    } else {
      indices = chunked_indices(sm.mesh, &g.chunks);
    }
    glGenVertexArrays(1, &g.vao);
    glBindVertexArray(g.vao);
    glGenBuffers(4, g.vbo);
    const std::vector<float>* attr[4] = {&mesh->positions, &mesh->normals, &mesh->uvs, &drop};
    const int comps[4] = {3, 3, 2, 1};
    for (int a = 0; a < 4; ++a) {
      if (a == 3 && drop.empty()) continue;  // no skirts: a_drop is the generic attribute's 0
      glBindBuffer(GL_ARRAY_BUFFER, g.vbo[a]);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(attr[a]->size() * sizeof(float)), attr[a]->data(),
                   GL_STATIC_DRAW);
      glEnableVertexAttribArray(static_cast<GLuint>(a));
      glVertexAttribPointer(static_cast<GLuint>(a), comps[a], GL_FLOAT, GL_FALSE, 0, nullptr);
    }
    glGenBuffers(1, &g.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    g.index_count = static_cast<GLsizei>(indices.size());
    glBindVertexArray(0);
    if (auto it = movable_local.find(meshes.size()); it != movable_local.end()) {
      MovablePart part;
      part.mesh = meshes.size();
      part.local = std::move(it->second.second);
      part.world = sm.mesh;
      part.world.indices = indices;  // chunk order: the chunks' index ranges
      movable[it->second.first].push_back(std::move(part));
      mesh_movable[meshes.size()] = true;
    }
    meshes.push_back(g);
  }
  build_caster_boxes(geo);
  mark_sun_free();
  for (GpuMesh& m : meshes) {
    bool mixed = false;               // a tile partly under another terrain mesh
    for (TerrainTile& t : m.tiles) {  // under another mesh when all its chunks are
      t.box.under = t.chunk_begin < t.chunk_end ? m.chunks[t.chunk_begin].under : -1;
      for (std::size_t c = t.chunk_begin; c < t.chunk_end; ++c) mixed = mixed || m.chunks[c].under != t.box.under;
    }
    // Terrain partly under other terrain (the far seabed, whose part under the patch occlusion
    // culling leaves out chunk by chunk): drawn by chunks, without levels of detail.
    if (mixed) m.tiles.clear();
  }
  check_gl("scene upload");
}

namespace {

constexpr double kCasterCellM = 0.5;  // caster boxes of objects, rocks and pipes: 0.5 m cells

// The box's extent along the unit axis a.
std::pair<float, float> box_interval(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, const Eigen::Vector3f& a) {
  const Eigen::Vector3f mid = 0.5f * (lo + hi), half = 0.5f * (hi - lo);
  const float m = a.dot(mid), r = half.dot(a.cwiseAbs());
  return {m - r, m + r};
}

}  // namespace

void Renderer::Impl::build_caster_boxes(const SceneGeometry& geo) {
  caster_boxes.clear();
  terrain_bounds.assign(meshes.size(), {Eigen::Vector3f::Constant(1e30f), Eigen::Vector3f::Constant(-1e30f)});
  deepest_z = -1e30f;
  for (const GpuMesh& m : meshes)
    for (const Chunk& c : m.chunks) deepest_z = std::max(deepest_z, c.hi.z());
  for (std::size_t mi = 0; mi < meshes.size(); ++mi)
    if (meshes[mi].terrain)
      for (const Chunk& c : meshes[mi].chunks) {
        terrain_bounds[mi].first = terrain_bounds[mi].first.cwiseMin(c.lo);
        terrain_bounds[mi].second = terrain_bounds[mi].second.cwiseMax(c.hi);
      }
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    if (meshes[mi].terrain) {  // the terrain casts on other terrain only (the patch's edge on the far seabed)
      for (Chunk& c : meshes[mi].chunks) {
        CasterBox box{mi, c.lo, c.hi};
        // Under another terrain mesh: inside its footprint (a full grid: its bounding rectangle)
        // and deeper than its deepest point.
        for (std::size_t pi = 0; pi < meshes.size(); ++pi) {
          const auto& [plo, phi] = terrain_bounds[pi];
          if (pi != mi && meshes[pi].terrain && c.lo.x() >= plo.x() && c.lo.y() >= plo.y() && c.hi.x() <= phi.x() &&
              c.hi.y() <= phi.y() && c.lo.z() > phi.z())
            box.under = static_cast<long>(pi);
        }
        c.under = box.under;
        caster_boxes.push_back(box);
      }
      continue;
    }
    add_object_casters(mi, geo.meshes[mi].mesh);
  }
}

void Renderer::Impl::add_object_casters(std::size_t mi, const MeshData& mesh) {
  std::map<std::pair<long, long>, std::size_t> cell_box;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto p = triangle_corners(mesh, t);
    const Eigen::Vector3f c = (p[0] + p[1] + p[2]) / 3.0f;
    const std::pair<long, long> key{std::lround(std::floor(c.x() / kCasterCellM)),
                                    std::lround(std::floor(c.y() / kCasterCellM))};
    auto [it, fresh] = cell_box.try_emplace(key, caster_boxes.size());
    if (fresh) caster_boxes.push_back({mi, p[0], p[0]});
    CasterBox& box = caster_boxes[it->second];
    for (const auto& q : p) {
      box.lo = box.lo.cwiseMin(q);
      box.hi = box.hi.cwiseMax(q);
    }
  }
}

// A movable object to X_WO: its parts' vertices and normals re-uploaded, their chunks' boxes and
// caster boxes remade, the terrain's sun-free marks refreshed.
void Renderer::Impl::move_object(std::vector<MovablePart>& parts, const Pose& X_WO) {
  for (MovablePart& part : parts) {
    part.world.positions = part.local.positions;
    part.world.normals = part.local.normals;
    part.world.transform(X_WO);
    GpuMesh& g = meshes[part.mesh];
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo[0]);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(part.world.positions.size() * sizeof(float)),
                    part.world.positions.data());
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo[1]);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(part.world.normals.size() * sizeof(float)),
                    part.world.normals.data());
    for (Chunk& ch : g.chunks) {
      ch.lo = Eigen::Vector3f::Constant(1e30f);
      ch.hi = Eigen::Vector3f::Constant(-1e30f);
      for (GLsizei i = ch.first; i < ch.first + ch.count; ++i) {
        const std::size_t v = 3 * static_cast<std::size_t>(part.world.indices[static_cast<std::size_t>(i)]);
        const Eigen::Vector3f q(part.world.positions[v], part.world.positions[v + 1], part.world.positions[v + 2]);
        ch.lo = ch.lo.cwiseMin(q);
        ch.hi = ch.hi.cwiseMax(q);
      }
    }
    caster_boxes.erase(std::remove_if(caster_boxes.begin(), caster_boxes.end(),
                                      [&](const CasterBox& c) { return c.mesh == part.mesh; }),
                       caster_boxes.end());
    add_object_casters(part.mesh, part.world);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  refresh_sun_free();
  sun_vp_cached.clear();  // the sun's map holds the object where it was
  check_gl("moving an object");
}

bool Renderer::Impl::casts_nothing(std::size_t mi, const Chunk& ch, const Eigen::Vector3f& L,
                                   const Eigen::Vector3f& eye) const {
  const GpuMesh& m = meshes[mi];
  if (!m.terrain) return false;
  if (!stands_over(mi, eye)) return false;
  const auto& [lo, hi] = terrain_bounds[mi];
  // The flattest lamp ray through the chunk: from the lamp to its shallowest, farthest corner.
  const float drop = ch.lo.z() - L.z();
  const float h_far =
      std::hypot(std::max(L.x() - ch.lo.x(), ch.hi.x() - L.x()), std::max(L.y() - ch.lo.y(), ch.hi.y() - L.y()));
  if (!(drop > 0.0f) || !(drop > m.tan_slope * h_far)) return false;
  const float sink = drop / std::max(h_far, 1e-6f);  // metres down per metre across, every ray
  // Leaving the footprint at least this far from the chunk, below all geometry (1 cm to spare).
  const float to_edge = std::min({ch.lo.x() - lo.x(), hi.x() - ch.hi.x(), ch.lo.y() - lo.y(), hi.y() - ch.hi.y()});
  return ch.lo.z() + sink * std::max(to_edge, 0.0f) >= deepest_z + 0.01f;
}

// Shadow receiver culling for the sun (static scene, fixed sun): a terrain chunk needs the sun's
// shadow lookup only if a caster can stand between it and the sun: a caster box of another mesh
// whose extent, seen along the sunlight, overlaps the chunk's and lies up-sun of some of it; or
// the terrain itself, when its steepest slope is at least the sun's elevation (from any point of a
// height field whose slopes are all flatter than the light, the ray to the sun rises faster than
// the ground can).
void Renderer::Impl::mark_sun_free() {
  // Casters grow by two texels of the sun's map: the PCF lookup reads the next texel too.
  const float pad = 4.0f * static_cast<float>(kSunShadowHalfM) /
                    static_cast<float>(std::min(4096, kSunMapScale * options.shadow_map_size));
  const Eigen::Vector3f s = world.sun.direction_W.normalized().cast<float>();
  const Eigen::Vector3f a = std::abs(s.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f u = (a - s * a.dot(s)).normalized(), v = s.cross(u);
  const float tan_elevation = s.z() > 1e-6f ? s.z() / std::hypot(s.x(), s.y()) : 0.0f;  // inf overhead
  sun_frame = {u, v, s};
  sun_pad = pad;
  // Each caster's extent along u, v (across the sunlight) and s (along it), once.
  std::vector<SunExtent> seen;
  seen.reserve(caster_boxes.size());
  for (const CasterBox& c : caster_boxes) seen.push_back(sun_extent(c.lo, c.hi));
  for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
    GpuMesh& m = meshes[mi];
    for (Chunk& r : m.chunks) r.sun_free = r.sun_free_static = false;
    if (!m.terrain || !(m.tan_slope < tan_elevation)) continue;
    for (Chunk& r : m.chunks) {
      const SunExtent re = sun_extent(r.lo, r.hi);
      bool blocked = false;
      for (std::size_t ci = 0; ci < caster_boxes.size() && !blocked; ++ci)
        blocked = caster_boxes[ci].mesh != mi && !mesh_movable[caster_boxes[ci].mesh] && may_shade(seen[ci], re);
      r.sun_free_static = !blocked;
    }
  }
  refresh_sun_free();
}

Renderer::Impl::SunExtent Renderer::Impl::sun_extent(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) const {
  const auto& [u, v, s] = sun_frame;
  return {{box_interval(lo, hi, u), box_interval(lo, hi, v), box_interval(lo, hi, s)}, lo.z(), hi.z()};
}

// Caster c can stand between the sun and receiver r: their extents across the sunlight overlap,
// c lies up-sun of some of r and reaches above r's deepest point (all grown by the PCF's pad).
bool Renderer::Impl::may_shade(const SunExtent& c, const SunExtent& r) const {
  const float pad = sun_pad;
  const auto &cu = c.along[0], &cv = c.along[1], &cs = c.along[2];
  const auto &ru = r.along[0], &rv = r.along[1], &rs = r.along[2];
  return cu.first <= ru.second + pad && ru.first <= cu.second + pad && cv.first <= rv.second + pad &&
         rv.first <= cv.second + pad && cs.first < rs.second + pad && c.top_z - pad <= r.bottom_z;
}

void Renderer::Impl::refresh_sun_free() {
  std::vector<SunExtent> moving;  // the movable objects' caster boxes
  for (const CasterBox& c : caster_boxes)
    if (mesh_movable[c.mesh]) moving.push_back(sun_extent(c.lo, c.hi));
  for (GpuMesh& m : meshes) {
    for (Chunk& r : m.chunks) {
      r.sun_free = r.sun_free_static;
      if (!r.sun_free || moving.empty()) continue;
      const SunExtent re = sun_extent(r.lo, r.hi);
      for (const SunExtent& c : moving) r.sun_free = r.sun_free && !may_shade(c, re);
    }
    for (TerrainTile& t : m.tiles) {  // sun-free when all its chunks are
      t.box.sun_free = true;
      for (std::size_t c = t.chunk_begin; c < t.chunk_end; ++c) t.box.sun_free = t.box.sun_free && m.chunks[c].sun_free;
    }
  }
}

void Renderer::Impl::upload_snow() {
  const auto& ms = world.marine_snow;
  const double n = ms.density_per_m3 * ms.box_m * ms.box_m * ms.box_m;
  snow_count = static_cast<GLsizei>(std::min(200000.0, std::max(0.0, n)));
  if (snow_count == 0) return;
  std::vector<float> seeds(static_cast<std::size_t>(snow_count) * 3);
  for (GLsizei i = 0; i < snow_count; ++i)
    for (int k = 0; k < 3; ++k) seeds[3 * i + k] = static_cast<float>(noise::lattice(i, k, 3, ms.seed));
  glGenVertexArrays(1, &snow_vao);
  glBindVertexArray(snow_vao);
  glGenBuffers(1, &snow_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, snow_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(seeds.size() * sizeof(float)), seeds.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindVertexArray(0);
}

}  // namespace unav::renderer

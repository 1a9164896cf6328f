// Scene geometry for the GPU: triangles in spatially compact chunks, terrain and rock levels of
// detail, frustum and shadow-extent tests, chunked draws (renderer_impl.hpp).
#include "renderer_impl.hpp"

#include <algorithm>
#include <limits>
#include <unordered_map>

namespace unav::renderer {

std::array<Eigen::Vector3f, 3> triangle_corners(const MeshData& mesh, std::size_t t) {
  std::array<Eigen::Vector3f, 3> p;
  for (std::size_t k = 0; k < 3; ++k)
    p[k] = Eigen::Map<const Eigen::Vector3f>(&mesh.positions[std::size_t{3} * mesh.indices[3 * t + k]]);
  return p;
}

float steepest_slope(const MeshData& mesh) {
  float best = 0.0f;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto p = triangle_corners(mesh, t);
    const Eigen::Vector3f n = (p[1] - p[0]).cross(p[2] - p[0]);
    const float horizontal = std::hypot(n.x(), n.y());
    if (horizontal == 0.0f) continue;
    if (std::abs(n.z()) < 1e-9f * horizontal) return std::numeric_limits<float>::infinity();
    best = std::max(best, horizontal / std::abs(n.z()));
  }
  return best;
}

// Triangles of a mesh reordered into chunks of about kChunkM x kChunkM (x, y) each.
constexpr double kChunkM = 2.0;
std::vector<std::uint32_t> chunked_indices(const MeshData& mesh, std::vector<Chunk>* chunks) {
  const std::size_t nt = mesh.triangle_count();
  const auto& P = mesh.positions;
  auto centroid = [&](std::size_t t, int axis) {
    double c = 0.0;
    for (int k = 0; k < 3; ++k)
      c += P[std::size_t{3} * mesh.indices[3 * t + static_cast<std::size_t>(k)] + static_cast<std::size_t>(axis)];
    return c / 3.0;
  };
  double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
  for (std::size_t t = 0; t < nt; ++t)
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min(lo[a], centroid(t, a));
      hi[a] = std::max(hi[a], centroid(t, a));
    }
  int n[2] = {1, 1};
  // At least ~8 triangles a chunk (a coarse mesh over a large area, as the far seabed, in few).
  const int most = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(nt) / 8.0)), 1, 64);
  if (nt > 2000)
    for (int a = 0; a < 2; ++a) n[a] = std::clamp(static_cast<int>(std::ceil((hi[a] - lo[a]) / kChunkM)), 1, most);
  std::vector<std::vector<std::size_t>> cells(static_cast<std::size_t>(n[0] * n[1]));
  for (std::size_t t = 0; t < nt; ++t) {
    int c[2];
    for (int a = 0; a < 2; ++a)
      c[a] =
          n[a] == 1 ? 0 : std::clamp(static_cast<int>((centroid(t, a) - lo[a]) / (hi[a] - lo[a]) * n[a]), 0, n[a] - 1);
    cells[static_cast<std::size_t>(c[0]) * static_cast<std::size_t>(n[1]) + static_cast<std::size_t>(c[1])].push_back(
        t);
  }
  std::vector<std::uint32_t> out;
  out.reserve(mesh.indices.size());
  for (const auto& cell : cells) {
    if (cell.empty()) continue;
    Chunk ch;
    ch.first = static_cast<GLsizei>(out.size());
    ch.lo.setConstant(std::numeric_limits<float>::infinity());
    ch.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t t : cell)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = mesh.indices[3 * t + static_cast<std::size_t>(k)];
        out.push_back(v);
        const std::size_t b = std::size_t{3} * v;
        const Eigen::Vector3f p(P[b], P[b + 1], P[b + 2]);
        ch.lo = ch.lo.cwiseMin(p);
        ch.hi = ch.hi.cwiseMax(p);
      }
    ch.count = static_cast<GLsizei>(out.size()) - ch.first;
    chunks->push_back(ch);
  }
  return out;
}

bool grid_layout(const MeshData& m, int* rows, int* cols) {
  const auto& P = m.positions;
  const std::size_t nv = m.vertex_count();
  std::size_t c = 1;
  while (c < nv && P[3 * c] == P[0]) ++c;
  if (c < 2 || nv % c != 0 || nv / c < 2 || nv > (std::size_t{1} << 30)) return false;
  const std::size_t r = nv / c;
  for (std::size_t i = 0; i < r; ++i)
    for (std::size_t j = 0; j < c; ++j) {
      const std::size_t v = 3 * (i * c + j);
      if (P[v] != P[3 * i * c] || P[v + 1] != P[3 * j + 1]) return false;
    }
  if (m.indices.size() != 6 * (r - 1) * (c - 1)) return false;
  std::size_t k = 0;
  for (std::size_t i = 0; i + 1 < r; ++i)
    for (std::size_t j = 0; j + 1 < c; ++j) {
      const std::size_t a = i * c + j, b = a + 1, e = a + c, d = e + 1;
      for (const std::size_t v : {a, b, e, b, d, e})
        if (m.indices[k++] != v) return false;
    }
  *rows = static_cast<int>(r);
  *cols = static_cast<int>(c);
  return true;
}

std::vector<std::uint32_t> terrain_lod(MeshData* mesh, int rows, int cols, std::vector<float>* drop,
                                       std::vector<Chunk>* chunks, std::vector<TerrainTile>* tiles, int* tile_cols,
                                       std::array<float, kLodLevels>* lift) {
  const auto id = [cols](int i, int j) { return static_cast<std::uint32_t>(i * cols + j); };
  const auto z = [&](int i, int j) { return mesh->positions[std::size_t{3} * id(i, j) + 2]; };
  std::vector<std::uint32_t> out;
  out.reserve(mesh->indices.size() * 2);
  const auto cell = [&](int i, int j, int s) {
    const std::uint32_t a = id(i, j), b = id(i, j + s), c = id(i + s, j), d = id(i + s, j + s);
    out.insert(out.end(), {a, b, c, b, d, c});
  };
  drop->assign(mesh->vertex_count(), 0.0f);
  // The chunk of indices [first, end), its box as drawn (skirt points dropped).
  const auto close = [&](std::size_t first) {
    Chunk ch;
    ch.first = static_cast<GLsizei>(first);
    ch.count = static_cast<GLsizei>(out.size() - first);
    ch.lo.setConstant(std::numeric_limits<float>::infinity());
    ch.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t k = first; k < out.size(); ++k) {
      const std::size_t b = std::size_t{3} * out[k];
      const Eigen::Vector3f p(mesh->positions[b], mesh->positions[b + 1], mesh->positions[b + 2] + (*drop)[out[k]]);
      ch.lo = ch.lo.cwiseMin(p);
      ch.hi = ch.hi.cwiseMax(p);
    }
    return ch;
  };
  const int ni = rows - 1, nj = cols - 1;  // cells
  const int tr = (ni + kTileCells - 1) / kTileCells, tc = (nj + kTileCells - 1) / kTileCells;
  *tile_cols = tc;
  tiles->assign(static_cast<std::size_t>(tr) * static_cast<std::size_t>(tc), TerrainTile{});
  struct Span {
    int i0, i1, j0, j1;  // the tile's cells
  };
  std::vector<Span> span(tiles->size());
  for (int a = 0; a < tr; ++a)
    for (int b = 0; b < tc; ++b) {
      const std::size_t ti = static_cast<std::size_t>(a) * static_cast<std::size_t>(tc) + static_cast<std::size_t>(b);
      Span& sp = span[ti];
      sp = {a * kTileCells, std::min((a + 1) * kTileCells, ni), b * kTileCells, std::min((b + 1) * kTileCells, nj)};
      TerrainTile& t = (*tiles)[ti];
      t.chunk_begin = chunks->size();
      for (int ci = sp.i0; ci < sp.i1; ci += kChunkCells)
        for (int cj = sp.j0; cj < sp.j1; cj += kChunkCells) {
          const std::size_t first = out.size();
          for (int i = ci; i < std::min(ci + kChunkCells, sp.i1); ++i)
            for (int j = cj; j < std::min(cj + kChunkCells, sp.j1); ++j) cell(i, j, 1);
          chunks->push_back(close(first));
        }
      t.chunk_end = chunks->size();
    }
  // Each coarse level's distance from the full mesh. Both are linear over the triangles of the
  // full mesh (a coarse cell's diagonal runs along the fine cells' diagonals), so the largest
  // distance lies at a grid point.
  std::array<float, kLodLevels> sink{};
  float worst = 0.0f;
  for (std::size_t ti = 0; ti < tiles->size(); ++ti) {
    const Span& sp = span[ti];
    TerrainTile& t = (*tiles)[ti];
    for (int k = 1; k < kLodLevels; ++k) {
      const int s = 1 << k;
      t.error[static_cast<std::size_t>(k)] = std::numeric_limits<float>::infinity();
      if ((sp.i1 - sp.i0) % s != 0 || (sp.j1 - sp.j0) % s != 0) continue;
      float e = 0.0f;
      for (int i = sp.i0; i <= sp.i1; ++i)
        for (int j = sp.j0; j <= sp.j1; ++j) {
          const int ci = sp.i0 + std::min((i - sp.i0) / s, (sp.i1 - sp.i0) / s - 1) * s;
          const int cj = sp.j0 + std::min((j - sp.j0) / s, (sp.j1 - sp.j0) / s - 1) * s;
          const float u = static_cast<float>(i - ci) / static_cast<float>(s);
          const float v = static_cast<float>(j - cj) / static_cast<float>(s);
          const float zc = u + v <= 1.0f ? z(ci, cj) + v * (z(ci, cj + s) - z(ci, cj)) + u * (z(ci + s, cj) - z(ci, cj))
                                         : z(ci + s, cj + s) + (1.0f - v) * (z(ci + s, cj) - z(ci + s, cj + s)) +
                                               (1.0f - u) * (z(ci, cj + s) - z(ci + s, cj + s));
          const float dz = zc - z(i, j);  // z down: > 0 where the coarse surface sags below the full one
          e = std::max(e, std::abs(dz));
          sink[static_cast<std::size_t>(k)] = std::max(sink[static_cast<std::size_t>(k)], dz);
        }
      t.error[static_cast<std::size_t>(k)] = e;
      worst = std::max(worst, e);
    }
  }
  // Neighbours at levels a and b part by at most error_a + error_b: skirts twice the worst, 2 cm more.
  const float skirt_m = 2.0f * worst + 0.02f;
  for (int k = 0; k < kLodLevels; ++k)
    (*lift)[static_cast<std::size_t>(k)] = k == 0 ? 0.0f : sink[static_cast<std::size_t>(k)] + 0.005f;
  const auto hang = [&](std::uint32_t v) {  // a copy of point v, drawn skirt_m below it
    const auto n = static_cast<std::uint32_t>(mesh->vertex_count());
    for (int a = 0; a < 3; ++a) mesh->positions.push_back(mesh->positions[std::size_t{3} * v + a]);
    for (int a = 0; a < 3; ++a) mesh->normals.push_back(mesh->normals[std::size_t{3} * v + a]);
    for (int a = 0; a < 2; ++a) mesh->uvs.push_back(mesh->uvs[std::size_t{2} * v + a]);
    drop->push_back(skirt_m);
    return n;
  };
  for (std::size_t ti = 0; ti < tiles->size(); ++ti) {
    const Span& sp = span[ti];
    TerrainTile& t = (*tiles)[ti];
    for (int k = 0; k < kLodLevels; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      if (!std::isfinite(t.error[kk])) continue;
      const int s = 1 << k;
      if (k > 0) {
        const std::size_t first = out.size();
        for (int i = sp.i0; i < sp.i1; i += s)
          for (int j = sp.j0; j < sp.j1; j += s) cell(i, j, s);
        t.level[kk] = close(first);
      }
      for (int side = 0; side < 4; ++side) {
        std::vector<std::uint32_t> top;
        if (side < 2) {
          for (int j = sp.j0; j <= sp.j1; j += s) top.push_back(id(side == 0 ? sp.i0 : sp.i1, j));
        } else {
          for (int i = sp.i0; i <= sp.i1; i += s) top.push_back(id(i, side == 2 ? sp.j0 : sp.j1));
        }
        std::vector<std::uint32_t> bottom;
        bottom.reserve(top.size());
        for (const std::uint32_t v : top) bottom.push_back(hang(v));
        const std::size_t first = out.size();
        for (std::size_t m = 0; m + 1 < top.size(); ++m)
          out.insert(out.end(), {top[m], top[m + 1], bottom[m + 1], top[m], bottom[m + 1], bottom[m]});
        t.skirt[kk][static_cast<std::size_t>(side)] = close(first);
      }
    }
    t.box.lo.setConstant(std::numeric_limits<float>::infinity());
    t.box.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (std::size_t c = t.chunk_begin; c < t.chunk_end; ++c) {
      t.box.lo = t.box.lo.cwiseMin((*chunks)[c].lo);
      t.box.hi = t.box.hi.cwiseMax((*chunks)[c].hi);
    }
    t.box.hi.z() += skirt_m;
  }
  return out;
}

std::vector<std::uint32_t> lod_indices(const SceneMesh& sm, std::vector<Chunk>* chunks,
                                       std::vector<GpuMesh::LodChunks>* lod, std::array<float, kLodLevels>* lift) {
  std::vector<std::uint32_t> out;
  lod->assign(sm.lod_parts.size(), {});
  lift->fill(0.0f);
  std::size_t levels = 0;
  for (const LodPart& p : sm.lod_parts) levels = std::max(levels, p.levels.size());
  if (levels > static_cast<std::size_t>(kLodLevels))
    throw std::invalid_argument(sm.name + ": " + std::to_string(levels) + " levels of detail (at most " +
                                std::to_string(kLodLevels) + ")");
  std::vector<Chunk> boxes(sm.lod_parts.size());  // each part's, shared by its levels
  for (std::size_t i = 0; i < sm.lod_parts.size(); ++i) {
    Chunk& box = boxes[i];
    box.lo.setConstant(std::numeric_limits<float>::infinity());
    box.hi.setConstant(-std::numeric_limits<float>::infinity());
    for (const std::uint32_t v : sm.lod_parts[i].levels[0]) {
      const Eigen::Vector3f q(sm.mesh.positions[3 * std::size_t{v}], sm.mesh.positions[3 * std::size_t{v} + 1],
                              sm.mesh.positions[3 * std::size_t{v} + 2]);
      box.lo = box.lo.cwiseMin(q);
      box.hi = box.hi.cwiseMax(q);
    }
  }
  for (std::size_t k = 0; k < levels; ++k)
    for (std::size_t i = 0; i < sm.lod_parts.size(); ++i) {
      const LodPart& p = sm.lod_parts[i];
      if (k >= p.levels.size()) continue;
      Chunk ch = boxes[i];
      ch.first = static_cast<GLsizei>(out.size());
      ch.count = static_cast<GLsizei>(p.levels[k].size());
      out.insert(out.end(), p.levels[k].begin(), p.levels[k].end());
      (*lod)[i].level.push_back(ch);
      (*lod)[i].error_m.push_back(static_cast<float>(p.error_m[k]));
      (*lift)[k] = std::max((*lift)[k], static_cast<float>(p.error_m[k]));
    }
  chunks->clear();
  for (const auto& l : *lod) chunks->push_back(l.level.front());
  return out;
}

int coarsest_level(const Chunk& box, const float* error, std::size_t levels, const Eigen::Vector3f& eye, float fx,
                   double px) {
  if (!(px > 0.0)) return 0;
  const float d = (eye.cwiseMax(box.lo).cwiseMin(box.hi) - eye).norm();
  for (std::size_t k = levels; k-- > 1;)
    if (fx * error[k] <= static_cast<float>(px) * d) return static_cast<int>(k);
  return 0;
}

int lod_level(const TerrainTile& t, const Eigen::Vector3f& eye, float fx, double px) {
  return coarsest_level(t.box, t.error.data(), t.error.size(), eye, fx, px);
}
std::size_t lod_level(const GpuMesh::LodChunks& p, const Eigen::Vector3f& eye, float fx, double px) {
  return static_cast<std::size_t>(coarsest_level(p.level.front(), p.error_m.data(), p.error_m.size(), eye, fx, px));
}

bool in_frustum(const Eigen::Matrix4f& vp, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector4f plane = vp.row(3) + (k & 1 ? -1.0f : 1.0f) * vp.row(k / 2);  // inside: plane . p >= 0
    const float inside = plane.x() * (plane.x() > 0.0f ? hi.x() : lo.x()) +
                         plane.y() * (plane.y() > 0.0f ? hi.y() : lo.y()) +
                         plane.z() * (plane.z() > 0.0f ? hi.z() : lo.z()) + plane.w();
    if (inside < 0.0f) return false;
  }
  return true;
}
bool in_frustum(const Eigen::Matrix4f& vp, const Chunk& ch) { return in_frustum(vp, ch.lo, ch.hi); }

float pcf_pad(float texel_per_m, const Eigen::Vector3f& L, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  const float far = (lo - L).cwiseAbs().cwiseMax((hi - L).cwiseAbs()).norm();
  return 2.0f * texel_per_m * far + 0.01f;
}

bool shadow_out_of_view(const Eigen::Matrix4f& vp_cam, const Eigen::Vector3f& L, const Eigen::Vector3f& axis,
                        float far_m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  int outside[6] = {0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 16; ++i) {
    Eigen::Vector3f p(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    if (i & 8) {
      const float along = (p - L).dot(axis);
      // A corner beside or behind the lamp, or on the far plane or past it (a ray through the box
      // may then leave it sideways before the plane): no such bound.
      if (!(along > 1e-3f) || !(along < far_m)) return false;
      p = L + (p - L) * (far_m / along);
    }
    const Eigen::Vector4f c = vp_cam * p.homogeneous();
    outside[0] += c.x() < -c.w();
    outside[1] += c.x() > c.w();
    outside[2] += c.y() < -c.w();
    outside[3] += c.y() > c.w();
    outside[4] += c.z() < -c.w();
    outside[5] += c.z() > c.w();
  }
  for (int k : outside)
    if (k == 16) return true;
  return false;
}

void draw_chunks(const std::vector<const Chunk*>& chunks) {
  GLsizei first = 0, count = 0;
  auto flush = [&] {
    if (count > 0)
      glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT,
                     // NOLINTNEXTLINE(performance-no-int-to-ptr): GL takes a buffer offset as a pointer
                     reinterpret_cast<const void*>(static_cast<std::uintptr_t>(first) * sizeof(std::uint32_t)));
    count = 0;
  };
  for (const Chunk* ch : chunks) {
    if (count > 0 && first + count == ch->first) {
      count += ch->count;
    } else {
      flush();
      first = ch->first;
      count = ch->count;
    }
  }
  flush();
}

}  // namespace unav::renderer

#include "unav_scene/scene_geometry.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

#include "unav_scene/errors.hpp"
#include "unav_scene/noise.hpp"

namespace unav::scene {

void MeshData::transform(const Pose& X, const Eigen::Vector3d& scale) {
  const Eigen::Matrix3d A = X.linear() * scale.asDiagonal();
  const Eigen::Matrix3d N = A.inverse().transpose();
  for (std::size_t i = 0; i < vertex_count(); ++i) {
    Eigen::Vector3d p(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
    p = A * p + X.translation();
    for (int k = 0; k < 3; ++k) positions[3 * i + k] = static_cast<float>(p[k]);
    if (normals.size() == positions.size()) {
      Eigen::Vector3d n(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
      n = (N * n).normalized();
      for (int k = 0; k < 3; ++k) normals[3 * i + k] = static_cast<float>(n[k]);
    }
  }
}

void MeshData::append(const MeshData& o) {
  const auto base = static_cast<std::uint32_t>(vertex_count());
  positions.insert(positions.end(), o.positions.begin(), o.positions.end());
  normals.insert(normals.end(), o.normals.begin(), o.normals.end());
  uvs.insert(uvs.end(), o.uvs.begin(), o.uvs.end());
  for (auto i : o.indices) indices.push_back(base + i);
}

std::map<std::string, std::vector<MovableMesh>> movable_meshes(const World& world, const SceneGeometry& geo) {
  std::map<std::string, std::vector<MovableMesh>> out;
  for (const Object& o : world.objects) {
    if (!o.movable) continue;
    const std::string key = "object:" + o.name;  // build_scene_geometry's name of its meshes
    for (std::size_t i = 0; i < geo.meshes.size(); ++i)
      if (geo.meshes[i].name == key) out[o.name].push_back({i, geo.meshes[i].object_frame});
  }
  return out;
}

std::size_t SceneGeometry::triangle_count() const {
  std::size_t n = 0;
  for (const auto& m : meshes) n += m.mesh.triangle_count();
  return n;
}

namespace {

void push3(std::vector<float>& v, const Eigen::Vector3d& p) {
  v.push_back(static_cast<float>(p.x()));
  v.push_back(static_cast<float>(p.y()));
  v.push_back(static_cast<float>(p.z()));
}

void compute_smooth_normals(MeshData& m) {
  std::vector<Eigen::Vector3d> acc(m.vertex_count(), Eigen::Vector3d::Zero());
  auto P = [&](std::uint32_t i) {
    const std::size_t k = 3 * std::size_t{i};
    return Eigen::Vector3d(m.positions[k], m.positions[k + 1], m.positions[k + 2]);
  };
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const auto a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
    const Eigen::Vector3d n = (P(b) - P(a)).cross(P(c) - P(a));  // area weighted
    acc[a] += n;
    acc[b] += n;
    acc[c] += n;
  }
  m.normals.clear();
  for (auto& n : acc) push3(m.normals, n.norm() > 0 ? n.normalized() : Eigen::Vector3d::UnitZ());
}

// Unit icosphere with `subdiv` subdivisions (shared vertices).
MeshData icosphere(int subdiv) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdiv; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      const auto id = static_cast<std::uint32_t>(v.size() - 1);
      mid[key] = id;
      return id;
    };
    std::vector<std::array<std::uint32_t, 3>> nf;
    for (const auto& tri : f) {
      const auto a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, c});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], c, b});
      nf.push_back({a, b, c});
    }
    f.swap(nf);
  }
  MeshData m;
  for (const auto& p : v) {
    push3(m.positions, p);
    push3(m.normals, p);
    m.uvs.push_back(static_cast<float>(std::atan2(p.y(), p.x())));
    m.uvs.push_back(static_cast<float>(std::acos(std::clamp(p.z(), -1.0, 1.0))));
  }
  for (const auto& tri : f) m.indices.insert(m.indices.end(), tri.begin(), tri.end());
  return m;
}

}  // namespace

MeshData make_sphere_mesh(double radius_m, int subdivisions) {
  MeshData m = icosphere(subdivisions);
  for (auto& x : m.positions) x = static_cast<float>(x * radius_m);
  return m;
}

MeshData make_rock_mesh(std::uint32_t seed, const Eigen::Vector3d& radii_m, int subdivisions) {
  MeshData m = icosphere(subdivisions);
  for (std::size_t i = 0; i < m.vertex_count(); ++i) {
    Eigen::Vector3d p(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
    // Large lumps + facets: two octaves of 3D value noise on the unit sphere.
    const double n1 = noise::value_noise3(1.7 * p.x() + 10, 1.7 * p.y() + 20, 1.7 * p.z() + 30, seed);
    const double n2 = noise::value_noise3(4.1 * p.x(), 4.1 * p.y(), 4.1 * p.z(), seed + 7U);
    double r = 1.0 + 0.45 * (n1 - 0.5) + 0.15 * (n2 - 0.5);
    Eigen::Vector3d q = r * p;
    if (q.z() > 0.35) q.z() = 0.35 + 0.3 * (q.z() - 0.35);  // flattened underside (NED z down)
    q = q.cwiseProduct(radii_m);
    for (int k = 0; k < 3; ++k) m.positions[3 * i + k] = static_cast<float>(q[k]);
  }
  compute_smooth_normals(m);
  return m;
}

namespace {

// Distance from p to the triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

}  // namespace

LodPart rock_lods(const MeshData& rock, int subdivisions) {
  LodPart part;
  part.levels.push_back(rock.indices);
  part.error_m.push_back(0.0);
  const auto P = [&rock](std::uint32_t i) {
    return Eigen::Vector3d(rock.positions[3 * std::size_t{i}], rock.positions[3 * std::size_t{i} + 1],
                           rock.positions[3 * std::size_t{i} + 2]);
  };
  const MeshData fine = icosphere(subdivisions);
  if (fine.vertex_count() != rock.vertex_count() || fine.triangle_count() != rock.triangle_count())
    throw std::invalid_argument("rock_lods: a mesh of " + std::to_string(rock.vertex_count()) + " vertices and " +
                                std::to_string(rock.triangle_count()) + " triangles is not an icosphere subdivided " +
                                std::to_string(subdivisions) + " times");
  for (int s = subdivisions - 1; s >= 0; --s) {
    const MeshData coarse = icosphere(s);  // its vertices: the rock's first ones, in the same order
    // The coarse surface's error: the farthest finest vertex from it (brute force: at most 320 x 642).
    double err = 0.0;
    for (std::size_t v = coarse.vertex_count(); v < rock.vertex_count(); ++v) {
      const Eigen::Vector3d p = P(static_cast<std::uint32_t>(v));
      double d = std::numeric_limits<double>::infinity();
      for (std::size_t t = 0; t < coarse.triangle_count(); ++t)
        d = std::min(d, point_triangle_distance(p, P(coarse.indices[3 * t]), P(coarse.indices[3 * t + 1]),
                                                P(coarse.indices[3 * t + 2])));
      err = std::max(err, d);
    }
    part.levels.push_back(coarse.indices);
    part.error_m.push_back(err);
  }
  return part;
}

MeshData make_box_mesh(const Eigen::Vector3d& size_m) {
  MeshData m;
  const Eigen::Vector3d h = 0.5 * size_m;
  for (int axis = 0; axis < 3; ++axis) {
    for (int sgn = -1; sgn <= 1; sgn += 2) {
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = sgn;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const auto base = static_cast<std::uint32_t>(m.vertex_count());
      for (int k = 0; k < 4; ++k) {
        Eigen::Vector3d p = n.cwiseProduct(h);
        p[u] = ((k == 1 || k == 2) ? 1 : -1) * h[u];
        p[v] = (k >= 2 ? 1 : -1) * h[v];
        push3(m.positions, p);
        push3(m.normals, n);
        m.uvs.push_back(static_cast<float>(p[u]));
        m.uvs.push_back(static_cast<float>(p[v]));
      }
      // Corners counter-clockwise about +axis: outward on the + face, reversed on the - face.
      if (sgn > 0)
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      else
        m.indices.insert(m.indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
    }
  }
  return m;
}

MeshData make_plane_mesh(double sx, double sy) {
  MeshData m;
  const double hx = 0.5 * sx, hy = 0.5 * sy;
  const Eigen::Vector3d c[4] = {{-hx, -hy, 0}, {hx, -hy, 0}, {hx, hy, 0}, {-hx, hy, 0}};
  for (const auto& p : c) {
    push3(m.positions, p);
    push3(m.normals, Eigen::Vector3d(0, 0, -1));
    m.uvs.push_back(static_cast<float>(p.x() + hx));
    m.uvs.push_back(static_cast<float>(p.y() + hy));
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

int closed_orientation(const MeshData& m) {
  const std::size_t nv = m.vertex_count(), nt = m.triangle_count();
  if (nt == 0) return 0;
  // Weld vertices at the same position (seams of uv or normals duplicate them): sorted, not a
  // tree, so that a scanned wreck of millions of triangles costs a sort, not a map per vertex.
  const auto pos = [&m](std::size_t i) {
    return std::array<float, 3>{m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]};
  };
  std::vector<std::uint32_t> order(nv);
  for (std::size_t i = 0; i < nv; ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&pos](std::uint32_t a, std::uint32_t b) { return pos(a) < pos(b); });
  std::vector<std::uint32_t> id(nv);
  std::uint32_t welded = 0;
  for (std::size_t k = 0; k < nv; ++k) {
    if (k > 0 && pos(order[k]) != pos(order[k - 1])) ++welded;
    id[order[k]] = welded;
  }
  ++welded;
  // Every directed edge once, and its reverse once; parts by union-find.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * nt);
  std::vector<std::uint32_t> parent(welded);
  for (std::uint32_t i = 0; i < welded; ++i) parent[i] = i;
  const auto root = [&parent](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t v[3] = {id[m.indices[3 * t]], id[m.indices[3 * t + 1]], id[m.indices[3 * t + 2]]};
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) return 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = v[k], b = v[(k + 1) % 3];
      edges.push_back((std::uint64_t{a} << 32) | b);
      parent[root(a)] = root(b);
    }
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return 0;  // an edge twice one way
  for (const std::uint64_t e : edges)
    if (!std::binary_search(edges.begin(), edges.end(), (e << 32) | (e >> 32))) return 0;  // no reverse
  // Signed volume of each connected part (divergence theorem; 6 x the volume). Closed parts:
  // independent of the origin; in double, exact enough tens of metres out.
  std::vector<double> volume(welded, 0.0);
  std::vector<char> part(welded, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) {
      const std::size_t i = m.indices[3 * t + k];
      p[k] = Eigen::Vector3d(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
    }
    const std::uint32_t r = root(id[m.indices[3 * t]]);
    volume[r] += p[0].dot(p[1].cross(p[2]));
    part[r] = 1;
  }
  int sign = 0;
  for (std::uint32_t r = 0; r < welded; ++r) {
    if (!part[r]) continue;
    const int s = volume[r] > 0.0 ? 1 : (volume[r] < 0.0 ? -1 : 0);
    if (s == 0 || (sign != 0 && s != sign)) return 0;
    sign = s;
  }
  return sign;
}

MeshData make_tube_mesh(const std::vector<Eigen::Vector3d>& C, double radius_m, int sides) {
  MeshData m;
  if (C.size() < 2) return m;
  // Parallel-transport frames: no twist along the bends.
  std::vector<Eigen::Vector3d> T(C.size());
  for (std::size_t i = 0; i < C.size(); ++i) {
    const Eigen::Vector3d& a = C[i == 0 ? 0 : i - 1];
    const Eigen::Vector3d& b = C[std::min(i + 1, C.size() - 1)];
    T[i] = (b - a).normalized();
  }
  // A ring whose neighbours share its tangent lies inside a straight run: the faces on either side
  // of it are one prism face cut in two (its vertices lie on the lines joining theirs, with the
  // same normals and uv linear in arc length), so it is left out. A 7 m run becomes one segment
  // instead of 70: a third of the triangles the lamps' shadow maps and the camera drew.
  constexpr double kStraight = 1e-9;  // |dT| of a straight run: rounding only
  std::vector<std::uint32_t> kept;    // centre-line indices with a ring
  for (std::size_t i = 0; i < C.size(); ++i) {
    const bool inner =
        i > 0 && i + 1 < C.size() && (T[i] - T[i - 1]).norm() < kStraight && (T[i + 1] - T[i]).norm() < kStraight;
    if (!inner) kept.push_back(static_cast<std::uint32_t>(i));
  }
  Eigen::Vector3d N = T[0].cross(Eigen::Vector3d::UnitZ());
  if (N.norm() < 1e-6) N = T[0].cross(Eigen::Vector3d::UnitX());
  N.normalize();
  double arc = 0.0;
  std::size_t next = 0;  // next entry of kept
  for (std::size_t i = 0; i < C.size(); ++i) {
    if (i > 0) {
      arc += (C[i] - C[i - 1]).norm();
      const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(T[i - 1], T[i]);
      N = (q * N).normalized();
      N = (N - T[i] * T[i].dot(N)).normalized();
    }
    if (kept[next] != i) continue;
    ++next;
    const Eigen::Vector3d B = T[i].cross(N);
    for (int s = 0; s <= sides; ++s) {
      const double a = 2.0 * M_PI * s / sides;
      // The seam's second copy (s = sides) sits exactly on the first (a closed solid).
      const double a_s = 2.0 * M_PI * (s % sides) / sides;
      const Eigen::Vector3d n = std::cos(a_s) * N + std::sin(a_s) * B;
      push3(m.positions, C[i] + radius_m * n);
      push3(m.normals, n);
      m.uvs.push_back(static_cast<float>(arc));
      m.uvs.push_back(static_cast<float>(a * radius_m));
    }
  }
  const auto ring = static_cast<std::uint32_t>(sides + 1);
  const auto rings = static_cast<std::uint32_t>(kept.size());
  for (std::uint32_t i = 0; i + 1 < rings; ++i)
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(sides); ++s) {
      const std::uint32_t a = i * ring + s, b = a + 1, c = a + ring, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, c, b, d, c});  // counter-clockwise seen from outside
    }
  // Flat end caps.
  for (int end = 0; end < 2; ++end) {
    const std::size_t i = end == 0 ? 0 : C.size() - 1;
    const Eigen::Vector3d n = end == 0 ? Eigen::Vector3d(-T[0]) : T.back();
    const auto centre = static_cast<std::uint32_t>(m.vertex_count());
    push3(m.positions, C[i]);
    push3(m.normals, n);
    m.uvs.insert(m.uvs.end(), {0.f, 0.f});
    const std::uint32_t first = (end == 0 ? 0 : rings - 1) * ring;
    for (int s = 0; s <= sides; ++s) {
      const std::uint32_t src = first + s;
      const std::size_t at = 3 * std::size_t{src};
      const float p[3] = {m.positions[at], m.positions[at + 1], m.positions[at + 2]};  // not a range of itself
      m.positions.insert(m.positions.end(), p, p + 3);
      push3(m.normals, n);
      m.uvs.insert(m.uvs.end(), {static_cast<float>(radius_m * std::cos(2 * M_PI * s / sides)),
                                 static_cast<float>(radius_m * std::sin(2 * M_PI * s / sides))});
    }
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(sides); ++s) {
      // The ring turns counter-clockwise about the tangent: outward at the end cap (+T), inward at the start (-T).
      if (end == 0)
        m.indices.insert(m.indices.end(), {centre, centre + 2 + s, centre + 1 + s});
      else
        m.indices.insert(m.indices.end(), {centre, centre + 1 + s, centre + 2 + s});
    }
  }
  return m;
}

MeshData make_seabed_mesh(const Seabed& sb) {
  MeshData m;
  const int nx = std::max(2, static_cast<int>(std::ceil(sb.size_m.x() / sb.resolution_m)) + 1);
  const int ny = std::max(2, static_cast<int>(std::ceil(sb.size_m.y() / sb.resolution_m)) + 1);
  const double n0 = sb.center_ne.x() - 0.5 * sb.size_m.x(), e0 = sb.center_ne.y() - 0.5 * sb.size_m.y();
  const double dn = sb.size_m.x() / (nx - 1), de = sb.size_m.y() / (ny - 1);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const double n = n0 + i * dn, e = e0 + j * de;
      const double z = sb.depth_at(n, e);
      // Normal from central differences of the depth field (NED: up is -z).
      const double h = 0.5 * std::min(dn, de);
      const double dzdn = (sb.depth_at(n + h, e) - sb.depth_at(n - h, e)) / (2 * h);
      const double dzde = (sb.depth_at(n, e + h) - sb.depth_at(n, e - h)) / (2 * h);
      push3(m.positions, Eigen::Vector3d(n, e, z));
      push3(m.normals, Eigen::Vector3d(dzdn, dzde, -1.0).normalized());
      m.uvs.push_back(static_cast<float>(n));
      m.uvs.push_back(static_cast<float>(e));
    }
  for (int i = 0; i + 1 < nx; ++i)
    for (int j = 0; j + 1 < ny; ++j) {
      const auto a = static_cast<std::uint32_t>(i * ny + j), b = a + 1, c = a + ny, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, c, b, d, c});
    }
  return m;
}

namespace {

// The triangles of one assimp mesh, in the file's frame.
MeshData mesh_of(const aiMesh* am) {
  MeshData m;
  for (unsigned v = 0; v < am->mNumVertices; ++v) {
    const auto& p = am->mVertices[v];
    m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
    const aiVector3D n = am->HasNormals() ? am->mNormals[v] : aiVector3D(0, 0, -1);
    m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
    const aiVector3D t = am->HasTextureCoords(0) ? am->mTextureCoords[0][v] : aiVector3D(0, 0, 0);
    m.uvs.insert(m.uvs.end(), {t.x, t.y});
  }
  for (unsigned f = 0; f < am->mNumFaces; ++f) {
    const aiFace& face = am->mFaces[f];
    if (face.mNumIndices != 3) continue;
    m.indices.insert(m.indices.end(), {face.mIndices[0], face.mIndices[1], face.mIndices[2]});
  }
  return m;
}

// Decoded rgb8, rows bottom first, from an OpenCV grey, BGR or BGRA image (8 or 16 bits).
std::shared_ptr<const TextureImage> to_texture(const cv::Mat& decoded, const std::string& source) {
  cv::Mat img = decoded;
  if (img.depth() == CV_16U) decoded.convertTo(img, CV_8U, 1.0 / 257.0);
  if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3 && img.channels() != 4))
    throw ConfigError(source + ": unsupported image format (expected 8 or 16-bit grey, RGB or RGBA)");
  const int ch = img.channels();
  auto t = std::make_shared<TextureImage>();
  t->width = img.cols;
  t->height = img.rows;
  t->source = source;
  t->rgb.resize(static_cast<std::size_t>(img.cols) * img.rows * 3);
  for (int r = 0; r < img.rows; ++r) {
    const auto* src = img.ptr<std::uint8_t>(img.rows - 1 - r);
    auto* dst = &t->rgb[static_cast<std::size_t>(r) * img.cols * 3];
    for (int c = 0; c < img.cols; ++c) {
      const std::uint8_t* px = src + static_cast<std::ptrdiff_t>(c) * ch;
      std::uint8_t* out = dst + static_cast<std::ptrdiff_t>(c) * 3;
      out[0] = ch == 1 ? px[0] : px[2];
      out[1] = ch == 1 ? px[0] : px[1];
      out[2] = px[0];
    }
  }
  return t;
}

// The first texture of material `mat` among `types`, decoded; null when it has none of them.
std::shared_ptr<const TextureImage> texture_of(const aiScene* scene, const aiMaterial* mat,
                                               std::initializer_list<aiTextureType> types,
                                               const std::string& mesh_path) {
  aiString tex;
  bool found = false;
  for (aiTextureType t : types)
    if (mat->GetTexture(t, 0, &tex) == AI_SUCCESS) {
      found = true;
      break;
    }
  if (!found) return nullptr;
  const std::string name = tex.C_Str();
  if (const aiTexture* embedded = scene->GetEmbeddedTexture(tex.C_Str())) {
    const std::string source = mesh_path + " (embedded texture '" + name + "')";
    if (embedded->mHeight == 0) {  // compressed (PNG, JPEG, ...): mWidth bytes
      const cv::Mat bytes(1, static_cast<int>(embedded->mWidth), CV_8U, const_cast<aiTexel*>(embedded->pcData));
      const cv::Mat img = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
      if (img.empty()) throw ConfigError(source + ": cannot decode the image");
      return to_texture(img, source);
    }
    cv::Mat bgra(static_cast<int>(embedded->mHeight), static_cast<int>(embedded->mWidth), CV_8UC4,
                 const_cast<aiTexel*>(embedded->pcData));  // aiTexel is b, g, r, a
    return to_texture(bgra.clone(), source);
  }
  const std::filesystem::path file = std::filesystem::path(mesh_path).parent_path() / name;
  const std::string source = mesh_path + ": texture '" + file.string() + "'";
  if (!std::filesystem::exists(file)) throw ConfigError(source + " not found");
  const cv::Mat img = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
  if (img.empty()) throw ConfigError(source + ": cannot read or decode the image");
  return to_texture(img, file.string());
}

// One occlusion-roughness-metallic image from the material's maps: occlusion from its map's red,
// roughness from its map's green, metallic from its map's blue (glTF packs all three so; a grey
// map has them all), 255 where a map is missing; at the largest map's size.
std::shared_ptr<const TextureImage> packed_orm(std::shared_ptr<const TextureImage> ao,
                                               std::shared_ptr<const TextureImage> rough,
                                               std::shared_ptr<const TextureImage> metal) {
  if (!ao && !rough && !metal) return nullptr;
  const std::array<std::shared_ptr<const TextureImage>, 3> maps = {std::move(ao), std::move(rough), std::move(metal)};
  if (maps[0] == maps[1] && maps[1] == maps[2]) return maps[0];  // one packed image
  auto out = std::make_shared<TextureImage>();
  for (const auto& m : maps)
    if (m && m->width * m->height > out->width * out->height) {
      out->width = m->width;
      out->height = m->height;
    }
  out->rgb.assign(static_cast<std::size_t>(out->width) * out->height * 3, 255);
  for (int c = 0; c < 3; ++c) {
    if (!maps[c]) continue;
    out->source += (out->source.empty() ? "" : " + ") + maps[c]->source;
    cv::Mat plane(maps[c]->height, maps[c]->width, CV_8UC3, const_cast<std::uint8_t*>(maps[c]->rgb.data()));
    cv::Mat channel;
    cv::extractChannel(plane, channel, c);
    if (channel.cols != out->width || channel.rows != out->height)
      cv::resize(channel, channel, cv::Size(out->width, out->height), 0, 0, cv::INTER_LINEAR);
    for (int r = 0; r < out->height; ++r)
      for (int x = 0; x < out->width; ++x)
        out->rgb[(static_cast<std::size_t>(r) * out->width + x) * 3 + c] = channel.at<std::uint8_t>(r, x);
  }
  return out;
}

// The maps of material `mi` (see SurfaceMaps); none when it has none.
SurfaceMaps maps_of(const aiScene* scene, unsigned mi, const std::string& mesh_path) {
  SurfaceMaps maps;
  if (mi >= scene->mNumMaterials) return maps;
  const aiMaterial* mat = scene->mMaterials[mi];
  maps.base_color = texture_of(scene, mat, {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}, mesh_path);
  maps.normal = texture_of(scene, mat, {aiTextureType_NORMALS, aiTextureType_NORMAL_CAMERA}, mesh_path);
  // glTF's metallicRoughnessTexture comes as both (and as "unknown" from older importers).
  auto rough = texture_of(scene, mat, {aiTextureType_DIFFUSE_ROUGHNESS, aiTextureType_UNKNOWN}, mesh_path);
  auto metal = texture_of(scene, mat, {aiTextureType_METALNESS, aiTextureType_UNKNOWN}, mesh_path);
  auto ao = texture_of(scene, mat, {aiTextureType_AMBIENT_OCCLUSION, aiTextureType_LIGHTMAP}, mesh_path);
  // The same file named twice decodes twice: compare sources to pack one image only once.
  if (rough && metal && rough->source == metal->source) metal = rough;
  if (ao && rough && ao->source == rough->source) ao = rough;
  maps.orm = packed_orm(std::move(ao), std::move(rough), std::move(metal));
  ai_real f = 1;
  if (mat->Get(AI_MATKEY_ROUGHNESS_FACTOR, f) == AI_SUCCESS && std::isfinite(f)) maps.roughness_factor = f;
  if (mat->Get(AI_MATKEY_METALLIC_FACTOR, f) == AI_SUCCESS && std::isfinite(f)) maps.metallic_factor = f;
  return maps;
}

const aiScene* read_mesh_file(Assimp::Importer& importer, const std::string& path) {
  {
    std::ifstream f(path, std::ios::binary);
    if (!f.good()) throw ConfigError(path + ": mesh file not found or not readable");
  }
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw ConfigError(path + ": cannot load mesh: " + importer.GetErrorString());
  return scene;
}

}  // namespace

std::vector<MeshPart> load_mesh_parts(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = read_mesh_file(importer, path);
  std::vector<MeshPart> parts(1);           // parts[0]: untextured
  std::map<unsigned, std::size_t> part_of;  // material -> its part (0: none of its own)
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    auto [it, first] = part_of.emplace(am->mMaterialIndex, 0);
    if (first && am->HasTextureCoords(0)) {
      if (SurfaceMaps maps = maps_of(scene, am->mMaterialIndex, path); maps.any()) {
        it->second = parts.size();
        parts.push_back({MeshData{}, std::move(maps)});
      }
    }
    parts[it->second].mesh.append(mesh_of(am));
  }
  std::vector<MeshPart> out;
  std::size_t triangles = 0;
  for (auto& p : parts) {
    triangles += p.mesh.triangle_count();
    if (p.mesh.triangle_count() > 0) out.push_back(std::move(p));
  }
  if (triangles == 0) throw ConfigError(path + ": mesh file contains no triangles");
  return out;
}

MeshData load_mesh_file(const std::string& path) {
  MeshData out;
  for (const MeshPart& p : load_mesh_parts(path)) out.append(p.mesh);
  return out;
}

void write_obj(const MeshData& m, const std::string& path) {
  std::ofstream f(path);
  if (!f) throw ConfigError(path + ": cannot write OBJ file");
  f << "# generated by unav_renderer (procedural rock)\n";
  f.precision(5);
  for (std::size_t i = 0; i < m.vertex_count(); ++i)
    f << "v " << m.positions[3 * i] << ' ' << m.positions[3 * i + 1] << ' ' << m.positions[3 * i + 2] << '\n';
  for (std::size_t i = 0; i < m.normals.size() / 3; ++i)
    f << "vn " << m.normals[3 * i] << ' ' << m.normals[3 * i + 1] << ' ' << m.normals[3 * i + 2] << '\n';
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    f << 'f';
    for (int k = 0; k < 3; ++k) f << ' ' << m.indices[3 * t + k] + 1 << "//" << m.indices[3 * t + k] + 1;
    f << '\n';
  }
  if (!f) throw ConfigError(path + ": write failed");
}

SceneGeometry build_scene_geometry(const World& w) {
  SceneGeometry g;
  if (w.seabed.enabled) {
    g.meshes.push_back({"seabed", make_seabed_mesh(w.seabed), SegClass::kSeabed, w.seabed.material, false, {}, {}, {}});
  }
  for (const auto& p : w.pipelines)
    g.meshes.push_back({"pipeline:" + p.name,
                        make_tube_mesh(p.centerline_W, p.radius_m, 16),
                        SegClass::kPipeline,
                        p.material,
                        false,
                        {},
                        {},
                        {}});
  // Rocks sharing a material are merged into one draw.
  std::vector<SceneMesh> rock_groups;
  for (const auto& r : w.rocks) {
    const int subdivisions = r.radii_m.maxCoeff() < 0.2 ? 1 : 2;
    MeshData m = make_rock_mesh(r.seed, r.radii_m, subdivisions);
    LodPart lods = rock_lods(m, subdivisions);  // before the pose: the errors are lengths, the same after it
    m.transform(pose_from_xyz_rpy(r.p_W, {0, 0, r.yaw_rad}));
    SceneMesh* grp = nullptr;
    for (auto& gm : rock_groups)
      if (same_look(gm.material, r.material)) grp = &gm;
    if (!grp) {
      rock_groups.push_back({"rocks", {}, SegClass::kRock, r.material, true, {}, {}, {}});
      grp = &rock_groups.back();
    }
    const auto base = static_cast<std::uint32_t>(grp->mesh.vertex_count());
    for (auto& level : lods.levels)
      for (auto& i : level) i += base;
    grp->mesh.append(m);
    grp->lod_parts.push_back(std::move(lods));
  }
  for (auto& gm : rock_groups) g.meshes.push_back(std::move(gm));
  if (w.seabed.enabled && w.seabed.far_extent_m > std::max(w.seabed.size_m.x(), w.seabed.size_m.y())) {
    // Coarse flat far seabed, below the detailed patch's lowest point; drawn last (early depth
    // test rejects it under the patch).
    Seabed far = w.seabed;
    far.size_m = {w.seabed.far_extent_m, w.seabed.far_extent_m};
    far.resolution_m = w.seabed.far_extent_m / 32.0;
    far.relief_amplitude_m = 0.0;
    far.hm_width = far.hm_height = 0;
    far.hm_values.clear();
    far.depth_m = w.seabed.depth_m + w.seabed.relief_amplitude_m + 0.2;
    g.meshes.push_back({"seabed_far", make_seabed_mesh(far), SegClass::kSeabed, w.seabed.material, false, {}, {}, {}});
  }
  for (const auto& o : w.objects) {
    MeshData m;
    if (!o.mesh_file.empty()) {
      std::vector<MeshPart> parts;
      try {
        parts = load_mesh_parts(o.mesh_file);
      } catch (const ConfigError& e) {
        throw ConfigError(w.file + ": object '" + o.name + "': " + e.what());
      }
      for (MeshPart& p : parts) {  // parts with maps by their UVs, the rest triplanar
        MeshData local;
        if (o.movable) {
          local = p.mesh;
          local.transform(Pose::Identity(), o.scale);
        }
        p.mesh.transform(o.X_WO, o.scale);
        const bool triplanar = !p.maps.any();
        g.meshes.push_back(
            {"object:" + o.name, std::move(p.mesh), o.seg_class, o.material, triplanar, p.maps, {}, std::move(local)});
      }
      continue;
    } else if (o.shape == "box") {
      m = make_box_mesh(o.size_m);
    } else if (o.shape == "sphere") {
      m = make_sphere_mesh(0.5 * o.size_m.x(), 3);
    } else {
      m = make_plane_mesh(o.size_m.x(), o.size_m.y());
    }
    MeshData local;
    if (o.movable) {
      local = m;
      local.transform(Pose::Identity(), o.scale);
    }
    m.transform(o.X_WO, o.scale);
    g.meshes.push_back(
        {"object:" + o.name, std::move(m), o.seg_class, o.material, o.shape != "plane", {}, {}, std::move(local)});
  }
  return g;
}

}  // namespace unav::scene

// Per-frame setup (camera, lamps, shadow matrices) and the shadow pass: a depth map per lamp
// and the sun's, with caster culling.
#include "renderer_impl.hpp"

#include <algorithm>
#include <limits>

#include "shaders.hpp"

namespace unav::renderer {

Renderer::Impl::FrameSetup Renderer::Impl::setup_frame(const Pose& X_WB, const CameraModel& c) const {
  FrameSetup f;
  f.X_WB = X_WB;
  f.X_WC = X_WB * c.X_BC;
  f.X_CW = f.X_WC.inverse();
  f.view = f.X_CW.matrix().cast<float>();
  f.proj = projection_from_K(c);
  f.cam_W = f.X_WC.translation();
  f.lod_fx = static_cast<float>(std::max(c.fx, c.fy));
  // Lamps in world and camera frames.
  f.nl = options.lamps ? static_cast<int>(std::min<std::size_t>(4, world.lamps.size())) : 0;
  for (int i = 0; i < f.nl; ++i) {
    const Lamp& L = world.lamps[i];
    const Pose X_WL = f.X_WB * L.X_BL;
    const Eigen::Vector3d pW = X_WL.translation(), dW = X_WL.linear().col(0).normalized();
    const Eigen::Vector3d pC = f.X_CW * pW, dC = f.X_CW.linear() * dW;
    for (int k = 0; k < 3; ++k) {
      f.lamp_pos_W[3 * i + k] = static_cast<float>(pW[k]);
      f.lamp_dir_W[3 * i + k] = static_cast<float>(dW[k]);
      f.lamp_pos_C[3 * i + k] = static_cast<float>(pC[k]);
      f.lamp_dir_C[3 * i + k] = static_cast<float>(dC[k]);
      f.lamp_I[3 * i + k] = static_cast<float>(L.intensity[k]);
    }
    f.lamp_cos[static_cast<std::size_t>(2 * i)] = static_cast<float>(std::cos(L.cone_half_angle_rad));
    f.lamp_cos[static_cast<std::size_t>(2 * i) + 1] = static_cast<float>(std::cos(0.55 * L.cone_half_angle_rad));
    // The lamp's shadow frustum: its cone (plus a margin) as a square perspective view.
    CameraModel lc;
    lc.width = lc.height = std::max(16, options.shadow_map_size);
    const double half = std::min(1.05 * L.cone_half_angle_rad + 0.02, 1.45);
    f.lamp_texel_per_m[i] = static_cast<float>(2.0 * std::tan(half) / std::max(16, options.shadow_map_size));
    lc.fx = lc.fy = 0.5 * lc.width / std::tan(half);
    lc.cx = lc.cy = 0.5 * lc.width - 0.5;
    lc.near_m = 0.05;
    lc.far_m = kLampFarM;
    Pose X_WLo = X_WL;
    X_WLo.linear() = X_WL.linear() * R_camera_body_to_optical();
    const Eigen::Matrix4f vp_W = projection_from_K(lc) * X_WLo.inverse().matrix().cast<float>();
    const Eigen::Matrix4f vp_C = vp_W * f.X_WC.matrix().cast<float>();
    std::copy(vp_W.data(), vp_W.data() + 16, f.shadow_vp_W + std::ptrdiff_t{16} * i);
    std::copy(vp_C.data(), vp_C.data() + 16, f.shadow_vp_C + std::ptrdiff_t{16} * i);
  }
  // The sun's shadow map: an orthographic view along the sunlight over a square of
  // 2 kSunShadowHalfM around the camera, its centre snapped to whole texels (no shimmering
  // as the camera moves).
  const Eigen::Vector3d sdir = world.sun.direction_W.normalized();
  f.sun_shadow = options.shadows && sdir.z() > 0.05 && world.sun.ambient_fraction < 1.0;
  if (f.sun_shadow) {
    const Eigen::Vector3d a = std::abs(sdir.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d xl = (a - sdir * a.dot(sdir)).normalized(), yl = sdir.cross(xl);
    const double cx = std::round(xl.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    const double cy = std::round(yl.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    // Along the light too, in steps: the matrix changes only when the camera has moved.
    const double cz = std::round(sdir.dot(f.cam_W) / kSunSnapM) * kSunSnapM;
    const Eigen::Vector3d centre = xl * cx + yl * cy + sdir * cz;
    const Eigen::Vector3d eye = centre - sdir * 60.0;  // a tight depth range: a small bias in metres
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.block<1, 3>(0, 0) = xl.transpose();
    view.block<1, 3>(1, 0) = yl.transpose();
    view.block<1, 3>(2, 0) = sdir.transpose();
    view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * eye;
    const double n = 1.0, far = 140.0;
    Eigen::Matrix4d proj = Eigen::Matrix4d::Zero();
    proj(0, 0) = proj(1, 1) = 1.0 / kSunShadowHalfM;
    proj(2, 2) = 2.0 / (far - n);
    proj(2, 3) = -(far + n) / (far - n);
    proj(3, 3) = 1.0;
    const Eigen::Matrix4f vp = (proj * view).cast<float>();
    std::copy(vp.data(), vp.data() + 16, f.sun_vp);
  }
  f.shadows = options.shadows && f.nl > 0;

  return f;
}

// Depth of the scene seen from each lamp (its shadow map), with a slope-scaled offset against
// self-shadowing. Both sides of every face: culling a solid's back faces here would let the front
// faces' offset decide the texels on its silhouette (-2 % of a frame's instructions, but shadow
// edges move by a texel at contact lines).
void Renderer::Impl::shadow_pass(const FrameSetup& f) {
  timings.lamp_map_triangles = timings.lamp_map_culled = 0;
  if (!f.shadows && !f.sun_shadow) return;
  const int size = options.shadow_map_size;
  if (shadow_size != size) {
    if (shadow_tex) glDeleteTextures(1, &shadow_tex);
    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, shadow_tex);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_DEPTH_COMPONENT32F, size, size, kShadowLayers, 0, GL_DEPTH_COMPONENT,
                 GL_FLOAT, nullptr);
    shadow_sampling(GL_TEXTURE_2D_ARRAY);
    if (sun_tex) glDeleteTextures(1, &sun_tex);
    sun_vp_cached.clear();
    glGenTextures(1, &sun_tex);
    glBindTexture(GL_TEXTURE_2D, sun_tex);
    const int sun_size = std::min(4096, kSunMapScale * size);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, sun_size, sun_size, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    shadow_sampling(GL_TEXTURE_2D);
    if (!shadow_fbo) glGenFramebuffers(1, &shadow_fbo);
    shadow_size = size;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  glViewport(0, 0, size, size);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_POLYGON_OFFSET_FILL);
  const auto bias = static_cast<float>(options.shadow_bias);
  glPolygonOffset(2.0f * bias, 4.0f * bias);
  shadow.use();
  const float one = 1.0f;
  const Eigen::Vector3f cam = f.cam_W.cast<float>();
  const Eigen::Matrix4f cam_vp = f.proj * f.view;
  // The sun's map depends on the static scene and its matrix only: reused until either changes.
  const bool sun_fresh =
      f.sun_shadow && sun_vp_cached.size() == 16 && std::equal(sun_vp_cached.begin(), sun_vp_cached.end(), f.sun_vp);
  for (int i = 0; i < (f.shadows ? f.nl : 0) + (f.sun_shadow && !sun_fresh ? 1 : 0); ++i) {
    const bool sun = f.sun_shadow && i == (f.shadows ? f.nl : 0);
    if (sun) sun_vp_cached.assign(f.sun_vp, f.sun_vp + 16);
    if (sun) {
      const int sun_size = std::min(4096, kSunMapScale * size);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, sun_tex, 0);
      glViewport(0, 0, sun_size, sun_size);
      glPolygonOffset(1.5f * bias, 2.0f * bias);
    } else {
      glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, shadow_tex, 0, i);
    }
    check_fbo("shadow map");
    glClearBufferfv(GL_DEPTH, 0, &one);
    const float* vp_data = sun ? f.sun_vp : f.shadow_vp_W + std::ptrdiff_t{16} * i;
    glUniformMatrix4fv(shadow["u_vp"], 1, GL_FALSE, vp_data);
    const Eigen::Matrix4f vp = Eigen::Map<const Eigen::Matrix4f>(vp_data);
    // The sun has no position: its map keeps the terrain hidden under other terrain (and is cached).
    const Eigen::Vector3f lamp =
        sun ? Eigen::Vector3f::Zero()
            : Eigen::Vector3f(Eigen::Map<const Eigen::Vector3f>(f.lamp_pos_W + std::ptrdiff_t{3} * i));
    const Eigen::Vector3f axis =
        sun ? Eigen::Vector3f::Zero()
            : Eigen::Vector3f(Eigen::Map<const Eigen::Vector3f>(f.lamp_dir_W + std::ptrdiff_t{3} * i));
    for (std::size_t mi = 0; mi < meshes.size(); ++mi) {
      const GpuMesh& m = meshes[mi];
      glBindVertexArray(m.vao);
      std::vector<const Chunk*> visible;
      visible.reserve(m.chunks.size());
      for (std::size_t ci = 0; ci < m.chunks.size(); ++ci) {
        const Chunk& ch = m.chunks[ci];
        if (!in_frustum(vp, ch)) continue;
        if (sun) {  // the finest (the map is kept while the sun stands still; see GpuMesh::lift)
          visible.push_back(&ch);
          continue;
        }
        if (options.occlusion_culling && hidden_under(ch.under, lamp)) continue;
        // A part at levels of detail: the level the camera sees (the lamps ride with it), which its
        // lookups of the lamp maps then find there.
        const Chunk& draw =
            m.lod.empty() ? ch : m.lod[ci].level[lod_level(m.lod[ci], cam, f.lod_fx, options.terrain_lod_px)];
        bool culled = false;
        if (caster_culling()) {
          const float pad = pcf_pad(f.lamp_texel_per_m[i], lamp, ch.lo, ch.hi);
          culled = (m.terrain && casts_nothing(mi, ch, lamp, cam)) ||
                   shadow_out_of_view(cam_vp, lamp, axis, kLampFarM, ch.lo.array() - pad, ch.hi.array() + pad);
        }
        (culled ? timings.lamp_map_culled : timings.lamp_map_triangles) += static_cast<std::size_t>(draw.count) / 3;
        if (!culled) visible.push_back(&draw);
      }
      draw_chunks(visible);
    }
  }
  glDisable(GL_POLYGON_OFFSET_FILL);
}

}  // namespace unav::renderer

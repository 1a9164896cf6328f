// A frame back to the CPU: asynchronous copies into pixel-buffer objects, fenced, collected
// oldest first; rgba -> rgb + segmentation.
#include "renderer_impl.hpp"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pixel_ops.hpp"

namespace unav::renderer {

// rgba8 -> rgb8 + the alpha plane (segmentation ids), four pixels per step as 32-bit words on
// little-endian machines (a third of the byte loop's instructions: 4 -> ~1.3 ms of CPU a VGA frame).
void detail::split_rgba(const std::uint8_t* rgba, std::size_t px, std::uint8_t* rgb, std::uint8_t* alpha) {
  std::size_t i = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  for (; i + 4 <= px; i += 4) {
    std::uint32_t p[4];
    std::memcpy(p, rgba + 4 * i, sizeof p);  // p[k] = r | g << 8 | b << 16 | a << 24
    const std::uint32_t out[3] = {(p[0] & 0xFFFFFFu) | (p[1] << 24), ((p[1] >> 8) & 0xFFFFu) | (p[2] << 16),
                                  ((p[2] >> 16) & 0xFFu) | (p[3] << 8)};
    const std::uint32_t a = (p[0] >> 24) | ((p[1] >> 16) & 0xFF00u) | ((p[2] >> 8) & 0xFF0000u) | (p[3] & 0xFF000000u);
    std::memcpy(rgb + 3 * i, out, sizeof out);
    std::memcpy(alpha + i, &a, sizeof a);
  }
#endif
  for (; i < px; ++i) {
    rgb[3 * i] = rgba[4 * i];
    rgb[3 * i + 1] = rgba[4 * i + 1];
    rgb[3 * i + 2] = rgba[4 * i + 2];
    alpha[i] = rgba[4 * i + 3];
  }
}

void detail::jpeg_roundtrip(std::uint8_t* rgb, int width, int height, int quality) {
  cv::Mat image(height, width, CV_8UC3, rgb), bgr;
  cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);  // libjpeg's YCbCr weights take OpenCV's BGR order
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, quality}))
    throw GlError("JPEG encoding of the camera image failed");
  const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (decoded.rows != height || decoded.cols != width) throw GlError("JPEG decoding of the camera image failed");
  cv::cvtColor(decoded, image, cv::COLOR_BGR2RGB);  // into rgb: `image` wraps it
}

void Renderer::Impl::start_readback(Slot& s, const Targets& t) {
  const std::size_t px = static_cast<std::size_t>(t.out_width) * t.out_height;
  if (s.pbo_rgba == 0) {
    glGenBuffers(1, &s.pbo_rgba);
    glGenBuffers(1, &s.pbo_depth);
  }
  if (s.capacity_px < px) {
    glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
    glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(px * 4), nullptr, GL_STREAM_READ);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
    glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(px * 4), nullptr, GL_STREAM_READ);
    s.capacity_px = px;
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, t.post_fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
  glReadPixels(0, 0, t.out_width, t.out_height, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
  glReadPixels(0, 0, t.out_width, t.out_height, GL_RED, GL_FLOAT, nullptr);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  if (s.timed) glQueryCounter(s.stamps[kStamps - 1], GL_TIMESTAMP);
  s.fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();
  check_gl("readback");
}

Frame Renderer::Impl::finish_readback(Slot& s) {
  Frame f = s.meta;
  const std::size_t px = static_cast<std::size_t>(f.width) * f.height;
  {
    const std::lock_guard<std::mutex> lock(spare_mutex);
    if (!spare.empty()) {  // its buffers: resize() below keeps their pages (same size: no writes)
      Frame& b = spare.back();
      f.rgb.swap(b.rgb);
      f.seg.swap(b.seg);
      f.depth.swap(b.depth);
      spare.pop_back();
    }
  }
  if (s.fence) {
    glClientWaitSync(s.fence, GL_SYNC_FLUSH_COMMANDS_BIT, 10'000'000'000ULL);
    glDeleteSync(s.fence);
    s.fence = nullptr;
  }
  if (s.timed) {  // all done with the fence: the results wait for nothing
    GLuint64 ns[kStamps] = {};
    for (int i = 0; i < kStamps; ++i) glGetQueryObjectui64v(s.stamps[i], GL_QUERY_RESULT, &ns[i]);
    double* const out[kStamps - 1] = {&timings.gpu_shadow_ms,    &timings.gpu_scene_ms, &timings.gpu_snow_ms,
                                      &timings.gpu_inscatter_ms, &timings.gpu_post_ms,  &timings.gpu_readback_ms};
    for (int i = 0; i + 1 < kStamps; ++i) *out[i] = 1e-6 * static_cast<double>(ns[i + 1] - ns[i]);
  }
  f.rgb.resize(px * 3);
  f.seg.resize(px);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_rgba);
  const auto* rgba = static_cast<const std::uint8_t*>(
      glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(px * 4), GL_MAP_READ_BIT));
  if (!rgba) throw GlError("glMapBufferRange failed for the colour readback");
  detail::split_rgba(rgba, px, f.rgb.data(), f.seg.data());
  glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
  if (s.jpeg_quality > 0) detail::jpeg_roundtrip(f.rgb.data(), f.width, f.height, s.jpeg_quality);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, s.pbo_depth);
  const auto* dz = static_cast<const float*>(
      glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(px * 4), GL_MAP_READ_BIT));
  if (!dz) throw GlError("glMapBufferRange failed for the depth readback");
  f.depth.assign(dz, dz + px);  // one pass (a resize would zero it first)
  glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  return f;
}

void Renderer::Impl::collect_oldest() {
  const auto t0 = Clock::now();
  const std::size_t idx = in_flight.front();
  in_flight.pop_front();
  done.push_back(finish_readback(slots[idx]));
  timings.readback_ms = ms_since(t0);
}

}  // namespace unav::renderer

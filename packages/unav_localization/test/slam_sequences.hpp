// The rendered image sequences the SLAM and VO tests run on, as files: the CTest fixture
// `render_slam_sequences` (test/render_slam_sequences.cpp, the one test here that links the
// renderer) draws every sequence once per test run into UNAV_SLAM_SEQUENCES; the estimator tests
// read them and need no EGL. A sequence holds what a test needs of the renderer's frames: the
// images (gray, or RGB for the node tests that publish them), optionally depth, the body and
// camera poses and the camera matrix.
//
// File `<name>.seq` (native byte order; written and read on the same machine): "UNAVSEQ1", int32
// width, height, channels (1 or 3), has_depth, count; 9 doubles K (row-major); per frame: double
// stamp, 16 doubles X_WB, 16 doubles X_WC (column-major 4x4), the image bytes (row-major,
// width * channels per row), then width * height floats of depth [m] if has_depth.
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace unav::localization::testing {

struct RenderedSequence {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d> X_WB;  ///< body in world
  std::vector<Eigen::Isometry3d> X_WC;  ///< camera optical frame in world
  std::vector<cv::Mat> images;          ///< CV_8UC1 (gray) or CV_8UC3 (RGB)
  std::vector<cv::Mat> depth;           ///< CV_32FC1 [m]; empty when not stored
  std::size_t size() const { return images.size(); }
};

inline constexpr char kSequenceMagic[8] = {'U', 'N', 'A', 'V', 'S', 'E', 'Q', '1'};

/// The file of sequence `name` in the fixture's folder.
inline std::string sequence_path(const std::string& name) {
#ifdef UNAV_SLAM_SEQUENCES
  return std::string(UNAV_SLAM_SEQUENCES) + "/" + name + ".seq";
#else
  return name + ".seq";
#endif
}

inline void save_sequence(const RenderedSequence& s, const std::string& path) {
  if (s.images.empty()) throw std::invalid_argument(path + ": a sequence without images");
  const cv::Mat& first = s.images.front();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot be written");
  auto put_i = [&](int32_t v) { out.write(reinterpret_cast<const char*>(&v), sizeof v); };
  auto put_d = [&](const double* d, std::size_t n) {
    out.write(reinterpret_cast<const char*>(d), static_cast<std::streamsize>(n * sizeof(double)));
  };
  out.write(kSequenceMagic, sizeof kSequenceMagic);
  put_i(first.cols);
  put_i(first.rows);
  put_i(first.channels());
  put_i(s.depth.empty() ? 0 : 1);
  put_i(static_cast<int32_t>(s.images.size()));
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> K = s.K;
  put_d(K.data(), 9);
  for (std::size_t k = 0; k < s.images.size(); ++k) {
    const cv::Mat& im = s.images[k];
    if (im.cols != first.cols || im.rows != first.rows || im.type() != first.type() || !im.isContinuous())
      throw std::invalid_argument(path + ": image " + std::to_string(k) + " differs from the first in size or type");
    put_d(&s.stamps[k], 1);
    put_d(s.X_WB[k].matrix().data(), 16);
    put_d(s.X_WC[k].matrix().data(), 16);
    out.write(reinterpret_cast<const char*>(im.data), static_cast<std::streamsize>(im.total() * im.elemSize()));
    if (!s.depth.empty()) {
      const cv::Mat& d = s.depth[k];
      if (d.type() != CV_32FC1 || d.cols != first.cols || d.rows != first.rows || !d.isContinuous())
        throw std::invalid_argument(path + ": depth " + std::to_string(k) + " is not a CV_32FC1 of the image's size");
      out.write(reinterpret_cast<const char*>(d.data), static_cast<std::streamsize>(d.total() * sizeof(float)));
    }
  }
  if (!out.flush()) throw std::runtime_error(path + ": write failed");
}

/// Reads sequence `name` (sequence_path); throws naming the file and what is wrong with it.
inline RenderedSequence load_sequence(const std::string& name) {
  const std::string path = sequence_path(name);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(path +
                             ": missing; the CTest fixture render_slam_sequences writes it (ctest runs it before "
                             "the tests that need it; run it by hand when a test binary runs alone)");
  char magic[8] = {};
  in.read(magic, sizeof magic);
  if (std::memcmp(magic, kSequenceMagic, sizeof magic) != 0) throw std::runtime_error(path + ": not a sequence file");
  auto get_i = [&] {
    int32_t v = 0;
    in.read(reinterpret_cast<char*>(&v), sizeof v);
    return v;
  };
  auto get_d = [&](double* d, std::size_t n) {
    in.read(reinterpret_cast<char*>(d), static_cast<std::streamsize>(n * sizeof(double)));
  };
  const int w = get_i(), h = get_i(), channels = get_i(), has_depth = get_i(), n = get_i();
  if (!in || w <= 0 || h <= 0 || (channels != 1 && channels != 3) || n <= 0)
    throw std::runtime_error(path + ": bad header");
  RenderedSequence s;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> K;
  get_d(K.data(), 9);
  s.K = K;
  for (int k = 0; k < n; ++k) {
    double stamp = 0.0;
    Eigen::Isometry3d X_WB, X_WC;
    get_d(&stamp, 1);
    get_d(X_WB.matrix().data(), 16);
    get_d(X_WC.matrix().data(), 16);
    cv::Mat im(h, w, channels == 1 ? CV_8UC1 : CV_8UC3);
    in.read(reinterpret_cast<char*>(im.data), static_cast<std::streamsize>(im.total() * im.elemSize()));
    s.stamps.push_back(stamp);
    s.X_WB.push_back(X_WB);
    s.X_WC.push_back(X_WC);
    s.images.push_back(im);
    if (has_depth != 0) {
      cv::Mat d(h, w, CV_32FC1);
      in.read(reinterpret_cast<char*>(d.data), static_cast<std::streamsize>(d.total() * sizeof(float)));
      s.depth.push_back(d);
    }
  }
  if (!in) throw std::runtime_error(path + ": truncated (" + std::to_string(n) + " frames announced)");
  return s;
}

}  // namespace unav::localization::testing

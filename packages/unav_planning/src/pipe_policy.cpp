#include "unav_planning/pipe_policy.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

namespace unav::planning {

struct OnnxPipePolicy::Impl {
  cv::dnn::Net net;
};

OnnxPipePolicy::OnnxPipePolicy(const std::string& model_path) : impl_(std::make_shared<Impl>()), path_(model_path) {
  std::ifstream probe(model_path, std::ios::binary);
  if (!probe) throw std::runtime_error("drl policy: model file '" + model_path + "' cannot be opened");
  std::ifstream meta(model_path + ".json");
  // (The graph outputs the unclipped mean action; act() clips it to [-1, 1].)
  if (!meta)
    throw std::runtime_error("drl policy: metadata '" + model_path +
                             ".json' (obs_shape) missing: export with "
                             "scripts/train_pipe_follower.py");
  try {
    const nlohmann::json j = nlohmann::json::parse(meta);
    const auto shape = j.at("obs_shape").get<std::vector<int>>();
    if (shape.size() != 3 || shape[2] != 3 || shape[0] < 1 || shape[1] < 1) throw std::runtime_error("not [h, w, 3]");
    height_ = shape[0];
    width_ = shape[1];
  } catch (const std::exception& e) {
    throw std::runtime_error("drl policy: '" + model_path + ".json': obs_shape: " + e.what());
  }
  try {
    impl_->net = cv::dnn::readNetFromONNX(model_path);
  } catch (const cv::Exception& e) {
    std::string why = e.msg;  // OpenCV's messages span lines: keep the error on one
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw std::runtime_error("drl policy: '" + model_path + "' is not a readable ONNX model: " + why);
  }
  impl_->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl_->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  // One dry run: a graph whose input is not the metadata's [h, w, 3] fails here, at start-up.
  try {
    (void)act(cv::Mat(height_, width_, CV_8UC3, cv::Scalar(0, 0, 0)));
  } catch (const std::exception& e) {
    std::string why = e.what();
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw std::runtime_error("drl policy: '" + model_path + "' does not run on a " + std::to_string(height_) + "x" +
                             std::to_string(width_) + "x3 image (obs_shape of its .json): " + why);
  }
}

std::array<double, 2> OnnxPipePolicy::act(const cv::Mat& rgb) {
  if (rgb.empty() || rgb.type() != CV_8UC3)
    throw std::invalid_argument("drl policy: expected an rgb8 image, got type " + std::to_string(rgb.type()));
  cv::Mat in;
  if (rgb.cols != width_ || rgb.rows != height_)
    cv::resize(rgb, in, cv::Size(width_, height_), 0, 0, cv::INTER_AREA);
  else
    in = rgb;
  cv::Mat f;
  in.convertTo(f, CV_32FC3);  // NHWC float 0..255, as exported
  const int dims[4] = {1, height_, width_, 3};
  cv::Mat blob(4, dims, CV_32F, f.ptr<float>());
  impl_->net.setInput(blob, "image");
  cv::Mat out = impl_->net.forward("action");
  if (out.total() != 2)
    throw std::runtime_error("drl policy: output has " + std::to_string(out.total()) + " values, not 2");
  const auto* o = out.ptr<float>();
  return {std::clamp(static_cast<double>(o[0]), -1.0, 1.0), std::clamp(static_cast<double>(o[1]), -1.0, 1.0)};
}

std::array<double, 2> ClassicalPipeFollower::act(const cv::Mat& rgb) {
  // 1. Edges: a pipe is two long, straight, parallel edges; sand ripples, rocks and particles
  //    give short or curved ones. Canny thresholds from Otsu's level of the blurred image (the
  //    usual heuristic: high = Otsu, low = high / 2).
  cv::Mat grey, blur, edges, scratch;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  cv::GaussianBlur(grey, blur, cv::Size(5, 5), 0.0);
  const double otsu = cv::threshold(blur, scratch, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  cv::Canny(blur, edges, 0.5 * otsu, otsu);
  // 2. Long straight segments.
  const int h = rgb.rows, w = rgb.cols;
  std::vector<cv::Vec4i> segs;
  cv::HoughLinesP(edges, segs, 1.0, CV_PI / 180.0, std::max(10, h / 4), std::max(10.0, 0.45 * h), h / 20.0);
  seen_ = false;
  if (segs.empty()) return {0.0, 0.0};
  // 3. Dominant orientation (length-weighted, undirected, 6 deg bins), then the segments along it.
  constexpr int kBins = 30;
  std::array<double, kBins> hist{};
  struct Seg {
    double angle, length, mx, my;  // midpoint relative to the image centre
  };
  std::vector<Seg> all;
  const double xc = 0.5 * (w - 1), yc = 0.5 * (h - 1);
  for (const auto& s : segs) {
    const double dx = s[2] - s[0], dy = s[3] - s[1];
    double ang = std::atan2(dy, dx);  // image axes: x right, y down
    if (ang < 0) ang += CV_PI;
    if (ang >= CV_PI) ang -= CV_PI;
    const double len = std::hypot(dx, dy);
    all.push_back({ang, len, 0.5 * (s[0] + s[2]) - xc, 0.5 * (s[1] + s[3]) - yc});
    hist[static_cast<std::size_t>(std::min(kBins - 1, static_cast<int>(ang / CV_PI * kBins)))] += len;
  }
  std::size_t best = 0;
  double best_w = 0;
  for (std::size_t b = 0; b < kBins; ++b) {  // circular 3-bin window
    const double wsum = hist[(b + kBins - 1) % kBins] + hist[b] + hist[(b + 1) % kBins];
    if (wsum > best_w) {
      best_w = wsum;
      best = b;
    }
  }
  const double centre = (best + 0.5) * CV_PI / kBins;
  double sx = 0, sy = 0, wsum = 0, lo = 1e9, hi = -1e9;
  for (const auto& s : all) {
    double d = std::abs(s.angle - centre);
    d = std::min(d, CV_PI - d);
    if (d > 1.5 * CV_PI / kBins) continue;
    // Average orientation on the doubled angle (undirected lines).
    sx += s.length * std::cos(2 * s.angle);
    sy += s.length * std::sin(2 * s.angle);
    wsum += s.length;
    // Offset of the segment along the dominant orientation's normal n = (-sin, cos).
    const double off = -std::sin(centre) * s.mx + std::cos(centre) * s.my;
    lo = std::min(lo, off);
    hi = std::max(hi, off);
  }
  if (wsum < 0.5 * h) return {0.0, 0.0};
  seen_ = true;
  const double axis = 0.5 * std::atan2(sy, sx);  // line direction angle in image coordinates
  // The pipe's two edges bound the offsets; its axis lies half-way (one edge seen: that edge,
  // off by a pipe radius at most).
  const double axis_offset = 0.5 * (lo + hi);
  // Direction along the axis pointing up the image (the vehicle's forward).
  double dx = std::cos(axis), dy = std::sin(axis);
  if (dy > 0) {
    dx = -dx;
    dy = -dy;
  }
  angle_rad_ = std::atan2(dx, -dy);  // > 0: the pipe runs to the right of the heading
  // The axis point closest to the image centre is centre + axis_offset n (n the normal of the
  // dominant orientation); its component along the vehicle's right (image (-dy, dx) for the
  // forward direction (dx, dy)) is the lateral offset, > 0 when the pipe is to the right.
  const double nx = -std::sin(centre), ny = std::cos(centre);
  const double lateral_px = axis_offset * (nx * -dy + ny * dx);
  const double f_px = 0.5 * w / std::tan(0.5 * p_.hfov_deg * M_PI / 180.0);
  lateral_m_ = lateral_px * p_.height_m / f_px;
  // Steer to the axis point lookahead_m ahead; turn to the axis direction.
  const double ahead_lat = lateral_m_ / std::max(0.2, std::cos(angle_rad_)) + p_.lookahead_m * std::tan(angle_rad_);
  const double step_dir = std::atan2(ahead_lat, p_.lookahead_m);
  auto ratio = [](double a, double max_deg) { return std::clamp(a / (max_deg * M_PI / 180.0), -1.0, 1.0); };
  return {ratio(step_dir, p_.max_step_angle_deg), ratio(p_.turn_gain * angle_rad_, p_.max_turn_deg)};
}

}  // namespace unav::planning

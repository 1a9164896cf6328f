#include "unav_datagen/dataset_writer.hpp"

#include "png_io.hpp"
#include "unav_datagen/manifest.hpp"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace unav::datagen {
namespace fs = std::filesystem;
using detail::write_png;

namespace detail {

void write_png(const std::string& root, const std::string& relative, const cv::Mat& m) {
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", m, png)) throw DatasetError(root + "/" + relative + ": PNG encoding failed");
  write_file_logged(root, relative, png);
}

cv::Mat depth_png(int width, int height, const float* depth_m, double units_per_metre) {
  cv::Mat d(height, width, CV_16UC1);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      d.at<std::uint16_t>(r, c) = encode_depth(
          depth_m[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c)],
          units_per_metre);
  return d;
}

}  // namespace detail

std::uint16_t encode_depth(float metres, double units_per_metre) {
  if (!std::isfinite(metres) || metres <= 0.0f) return 0;
  const double v = std::round(static_cast<double>(metres) * units_per_metre);
  return v > 65535.0 ? 0 : static_cast<std::uint16_t>(v);
}

namespace {

std::ofstream open_text(const std::string& path, const char* header) {
  std::ofstream f(path);
  if (!f) throw DatasetError(path + ": cannot be written");
  f << "# " << header << "\n" << std::setprecision(9) << std::fixed;
  f.flush();
  return f;
}

void pose_line(std::ofstream& f, double stamp, const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  const Eigen::Vector3d p = X.translation();
  f << stamp << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
    << q.w() << '\n';
  f.flush();
}

}  // namespace

DatasetWriter::DatasetWriter(const std::string& root) : SequenceWriter(root) {
  std::error_code ec;
  for (const char* sub : {"rgb", "depth", "segmentation"}) {
    fs::create_directories(fs::path(root) / sub, ec);
    if (ec) throw DatasetError(root + "/" + sub + ": cannot create folder: " + ec.message());
  }
  rgb_txt_ = open_text(root + "/rgb.txt", "timestamp filename (rgb8 PNG)");
  depth_txt_ = open_text(root + "/depth.txt", "timestamp filename (uint16 PNG, metres * 5000)");
  seg_txt_ = open_text(root + "/segmentation.txt",
                       "timestamp filename (class ids: 0 water 1 seabed 2 pipeline 3 rock 4 other)");
  gt_txt_ = open_text(root + "/groundtruth.txt", "timestamp tx ty tz qx qy qz qw (camera optical frame in world_ned)");
  gt_body_txt_ =
      open_text(root + "/groundtruth_body.txt", "timestamp tx ty tz qx qy qz qw (base_link_frd in world_ned)");
  imu_txt_ = open_text(root + "/imu.txt", "timestamp wx wy wz [rad/s] ax ay az [m/s^2] (base_link_frd)");
}

DatasetWriter::~DatasetWriter() { close(); }

void DatasetWriter::close() {
  for (auto* f : {&rgb_txt_, &depth_txt_, &seg_txt_, &gt_txt_, &gt_body_txt_, &imu_txt_})
    if (f->is_open()) f->close();
}

std::string DatasetWriter::stamp_name(double stamp) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(6) << stamp;
  return os.str();
}

void DatasetWriter::write_camera(const CameraIntrinsics& k) {
  std::ofstream f(root_ + "/camera.yaml");
  if (!f) throw DatasetError(root_ + "/camera.yaml: cannot be written");
  f << std::setprecision(12) << "# pinhole + plumb_bob (OpenCV order), pixels\nwidth: " << k.width
    << "\nheight: " << k.height << "\nfx: " << k.fx << "\nfy: " << k.fy << "\ncx: " << k.cx << "\ncy: " << k.cy
    << "\ndistortion: [";
  for (size_t i = 0; i < k.distortion.size(); ++i) f << (i ? ", " : "") << k.distortion[i];
  f << "]\ndepth_scale: " << kDepthScale << "\n";
}

void DatasetWriter::write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) {
  const std::string name = "rgb/" + stamp_name(stamp) + ".png";
  cv::Mat in(height, width, CV_8UC3, const_cast<std::uint8_t*>(rgb)), bgr;
  cv::cvtColor(in, bgr, cv::COLOR_RGB2BGR);
  write_png(root_, name, bgr);
  rgb_txt_ << stamp << ' ' << name << '\n';
  rgb_txt_.flush();
  ++counts_.images;
}

void DatasetWriter::write_depth(double stamp, int width, int height, const float* depth_m) {
  const std::string name = "depth/" + stamp_name(stamp) + ".png";
  write_png(root_, name, detail::depth_png(width, height, depth_m, kDepthScale));
  depth_txt_ << stamp << ' ' << name << '\n';
  depth_txt_.flush();
  ++counts_.depth;
}

void DatasetWriter::write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) {
  const std::string name = "segmentation/" + stamp_name(stamp) + ".png";
  write_png(root_, name, cv::Mat(height, width, CV_8UC1, const_cast<std::uint8_t*>(ids)));
  seg_txt_ << stamp << ' ' << name << '\n';
  seg_txt_.flush();
  ++counts_.segmentation;
}

void DatasetWriter::write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB) {
  pose_line(gt_txt_, stamp, X_WC);
  pose_line(gt_body_txt_, stamp, X_WB);
  ++counts_.poses;
}

void DatasetWriter::write_imu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  imu_txt_ << stamp << ' ' << gyro.x() << ' ' << gyro.y() << ' ' << gyro.z() << ' ' << accel.x() << ' ' << accel.y()
           << ' ' << accel.z() << '\n';
  imu_txt_.flush();
  ++counts_.imu;
}

}  // namespace unav::datagen

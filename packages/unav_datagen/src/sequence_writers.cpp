// EuRoC/ASL and KITTI odometry writers and the layout factory (see euroc_writer.hpp,
// kitti_writer.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_datagen/dataset_writer.hpp"
#include "unav_datagen/euroc_writer.hpp"
#include "unav_datagen/kitti_writer.hpp"

#include "png_io.hpp"
#include "unav_datagen/manifest.hpp"

namespace unav::datagen {
namespace fs = std::filesystem;
using detail::depth_png;
using detail::write_png;

namespace {

void make_dirs(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw DatasetError(dir + ": cannot create folder: " + ec.message());
}

std::ofstream open_out(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw DatasetError(path + ": cannot be written");
  return f;
}

cv::Mat grey_of(int width, int height, const std::uint8_t* rgb) {
  cv::Mat in(height, width, CV_8UC3, const_cast<std::uint8_t*>(rgb)), grey;
  cv::cvtColor(in, grey, cv::COLOR_RGB2GRAY);
  return grey;
}

// Rate of a stream from its first and last stamp and its count (0 with fewer than 2 samples).
double rate_hz(long long first_ns, long long last_ns, std::size_t n) {
  if (n < 2 || last_ns <= first_ns) return 0.0;
  return static_cast<double>(n - 1) / (static_cast<double>(last_ns - first_ns) * 1e-9);
}

std::string matrix_rows(const Eigen::Matrix4d& T) {
  std::ostringstream os;
  os << std::setprecision(12);
  for (int r = 0; r < 4; ++r) {
    os << (r == 0 ? "[" : "         ");
    for (int c = 0; c < 4; ++c) os << T(r, c) << (c < 3 ? ", " : r < 3 ? "," : "]");
    if (r < 3) os << "\n";
  }
  return os.str();
}

}  // namespace

std::vector<std::string> sequence_formats() { return {"tum", "euroc", "kitti"}; }

std::unique_ptr<SequenceWriter> make_sequence_writer(const std::string& format, const std::string& root) {
  if (format == "tum") return std::make_unique<DatasetWriter>(root);
  if (format == "euroc") return std::make_unique<EurocWriter>(root);
  if (format == "kitti") return std::make_unique<KittiWriter>(root);
  throw DatasetError("unknown dataset format '" + format + "' (valid: tum, euroc, kitti)");
}

// ---------------------------------------------------------------- EuRoC

long long EurocWriter::to_ns(double stamp) { return std::llround(stamp * 1e9); }

EurocWriter::EurocWriter(const std::string& root) : SequenceWriter(root), mav_(root + "/mav0") {
  make_dirs(mav_ + "/cam0/data");
  make_dirs(mav_ + "/imu0");
  make_dirs(mav_ + "/state_groundtruth_estimate0");
  make_dirs(mav_ + "/depth0/data");
  make_dirs(mav_ + "/seg0/data");
  cam_csv_ = open_out(mav_ + "/cam0/data.csv");
  cam_csv_ << "#timestamp [ns],filename\n" << std::flush;
  depth_csv_ = open_out(mav_ + "/depth0/data.csv");
  depth_csv_ << "#timestamp [ns],filename\n" << std::flush;
  seg_csv_ = open_out(mav_ + "/seg0/data.csv");
  seg_csv_ << "#timestamp [ns],filename\n" << std::flush;
  imu_csv_ = open_out(mav_ + "/imu0/data.csv");
  imu_csv_ << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
              "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
           << std::setprecision(9) << std::flush;
  gt_csv_ = open_out(mav_ + "/state_groundtruth_estimate0/data.csv");
  gt_csv_ << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n"
          << std::setprecision(9) << std::flush;
}

EurocWriter::~EurocWriter() { close(); }

void EurocWriter::write_camera(const CameraIntrinsics& k) {
  k_ = k;
  have_k_ = true;
  write_sensor_yamls();
}

void EurocWriter::set_camera_mount(const Eigen::Isometry3d& X_BC) {
  X_BC_ = X_BC;
  have_mount_ = true;
  write_sensor_yamls();
}

void EurocWriter::write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) {
  const long long ns = to_ns(stamp);
  const std::string name = std::to_string(ns) + ".png";
  write_png(root(), "mav0/cam0/data/" + name, grey_of(width, height, rgb));
  cam_csv_ << ns << ',' << name << '\n' << std::flush;
  images_.add(ns);
  ++counts_.images;
}

void EurocWriter::write_depth(double stamp, int width, int height, const float* depth_m) {
  const long long ns = to_ns(stamp);
  const std::string name = std::to_string(ns) + ".png";
  write_png(root(), "mav0/depth0/data/" + name, depth_png(width, height, depth_m, kDepthUnitsPerMetre));
  depth_csv_ << ns << ',' << name << '\n' << std::flush;
  ++counts_.depth;
}

void EurocWriter::write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) {
  const long long ns = to_ns(stamp);
  const std::string name = std::to_string(ns) + ".png";
  write_png(root(), "mav0/seg0/data/" + name, cv::Mat(height, width, CV_8UC1, const_cast<std::uint8_t*>(ids)));
  seg_csv_ << ns << ',' << name << '\n' << std::flush;
  ++counts_.segmentation;
}

void EurocWriter::write_pose(double stamp, const Eigen::Isometry3d& /*X_WC*/, const Eigen::Isometry3d& X_WB) {
  const Eigen::Quaterniond q(X_WB.linear());
  const Eigen::Vector3d p = X_WB.translation();
  gt_csv_ << to_ns(stamp) << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << q.w() << ',' << q.x() << ','
          << q.y() << ',' << q.z() << '\n'
          << std::flush;
  ++counts_.poses;
}

void EurocWriter::write_imu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  const long long ns = to_ns(stamp);
  imu_csv_ << ns << ',' << gyro.x() << ',' << gyro.y() << ',' << gyro.z() << ',' << accel.x() << ',' << accel.y() << ','
           << accel.z() << '\n'
           << std::flush;
  imu_.add(ns);
  ++counts_.imu;
}

void EurocWriter::write_sensor_yamls() {
  std::ofstream cam = open_out(mav_ + "/cam0/sensor.yaml");
  cam << std::setprecision(12) << "# General sensor definitions.\nsensor_type: camera\n"
      << "comment: \"UNav-Sim simulated camera, grey images; optical frame x right, y down, z forward\"\n"
      << "# Sensor extrinsics wrt. the body-frame (base_link_frd)"
      << (have_mount_ ? "" : "; NOT KNOWN when written: identity")
      << ".\nT_BS:\n  cols: 4\n  rows: 4\n  data: " << matrix_rows(X_BC_.matrix())
      << "\n# Camera specific definitions.\nrate_hz: " << rate_hz(images_.first_ns, images_.last_ns, counts_.images)
      << "\nresolution: [" << k_.width << ", " << k_.height << "]\ncamera_model: pinhole\nintrinsics: [" << k_.fx
      << ", " << k_.fy << ", " << k_.cx << ", " << k_.cy << "] #fu, fv, cu, cv\n"
      << "distortion_model: radial-tangential\ndistortion_coefficients: [";
  for (std::size_t i = 0; i < 4; ++i) cam << (i ? ", " : "") << (i < k_.distortion.size() ? k_.distortion[i] : 0.0);
  cam << "]\n";
  if (k_.distortion.size() > 4 && k_.distortion[4] != 0.0)
    cam << "# k3 = " << k_.distortion[4] << " is not representable in radial-tangential (k1 k2 p1 p2)\n";
  std::ofstream imu = open_out(mav_ + "/imu0/sensor.yaml");
  imu << std::setprecision(12) << "# General sensor definitions.\nsensor_type: imu\n"
      << "comment: \"UNav-Sim simulated IMU at the body origin (base_link_frd); noise in the vehicle YAML\"\n"
      << "T_BS:\n  cols: 4\n  rows: 4\n  data: " << matrix_rows(Eigen::Matrix4d::Identity())
      << "\nrate_hz: " << rate_hz(imu_.first_ns, imu_.last_ns, counts_.imu) << "\n";
}

void EurocWriter::close() {
  if (closed_) return;
  closed_ = true;
  for (auto* f : {&cam_csv_, &imu_csv_, &gt_csv_, &depth_csv_, &seg_csv_})
    if (f->is_open()) f->close();
  try {
    write_sensor_yamls();  // with the measured rates
  } catch (const DatasetError&) {
    // Nothing to report to from a destructor; the CSV files are complete.
  }
}

std::vector<std::string> EurocWriter::warnings() const {
  std::vector<std::string> w;
  if (!have_k_) w.push_back(mav_ + "/cam0/sensor.yaml: no camera_info arrived: intrinsics are zero");
  if (!have_mount_) w.push_back(mav_ + "/cam0/sensor.yaml: the camera mount was not known: T_BS is identity");
  return w;
}

// ---------------------------------------------------------------- KITTI

KittiWriter::KittiWriter(const std::string& root, const std::string& sequence)
    : SequenceWriter(root), seq_dir_(root + "/sequences/" + sequence) {
  make_dirs(seq_dir_ + "/image_0");
  make_dirs(seq_dir_ + "/depth_0");
  make_dirs(seq_dir_ + "/seg_0");
  make_dirs(root + "/poses");
  times_ = open_out(seq_dir_ + "/times.txt");
  times_ << std::scientific << std::setprecision(6);
  poses_ = open_out(root + "/poses/" + sequence + ".txt");
  poses_ << std::scientific << std::setprecision(9);
}

KittiWriter::~KittiWriter() { close(); }

void KittiWriter::write_camera(const CameraIntrinsics& k) {
  std::ofstream f = open_out(seq_dir_ + "/calib.txt");
  f << std::scientific << std::setprecision(12) << "P0: " << k.fx << ' ' << 0.0 << ' ' << k.cx << ' ' << 0.0 << ' '
    << 0.0 << ' ' << k.fy << ' ' << k.cy << ' ' << 0.0 << ' ' << 0.0 << ' ' << 0.0 << ' ' << 1.0 << ' ' << 0.0 << '\n';
  distorted_ = std::any_of(k.distortion.begin(), k.distortion.end(), [](double d) { return d != 0.0; });
}

void KittiWriter::write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) {
  std::ostringstream name;
  name << std::setw(6) << std::setfill('0') << image_stamps_.size() << ".png";
  write_png(root(), seq_dir_.substr(root().size() + 1) + "/image_0/" + name.str(), grey_of(width, height, rgb));
  image_stamps_.push_back(stamp);
  ++counts_.images;
  times_ << stamp - image_stamps_.front() << '\n' << std::flush;
  const auto [lo, hi] = pending_.equal_range(stamp);
  for (auto it = lo; it != hi; ++it) write_per_pixel(image_stamps_.size() - 1, it->second);
  pending_.erase(lo, hi);
}

namespace {

// Index of the image with this stamp (the newest first: depth and labels follow their image).
std::optional<std::size_t> index_of(const std::vector<double>& stamps, double stamp) {
  for (std::size_t i = stamps.size(); i-- > 0;)
    if (stamps[i] == stamp) return i;
  return std::nullopt;
}

}  // namespace

// Depth and labels are encoded when they arrive (the caller's buffers are not kept).
void KittiWriter::write_depth(double stamp, int width, int height, const float* depth_m) {
  Png png{true, {}};
  if (!cv::imencode(".png", depth_png(width, height, depth_m, kDepthUnitsPerMetre), png.second))
    throw DatasetError(seq_dir_ + "/depth_0: PNG encoding failed");
  put(stamp, std::move(png));
}

void KittiWriter::write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) {
  Png png{false, {}};
  if (!cv::imencode(".png", cv::Mat(height, width, CV_8UC1, const_cast<std::uint8_t*>(ids)), png.second))
    throw DatasetError(seq_dir_ + "/seg_0: PNG encoding failed");
  put(stamp, std::move(png));
}

void KittiWriter::put(double stamp, Png png) {
  if (const auto i = index_of(image_stamps_, stamp))
    write_per_pixel(*i, png);
  else
    pending_.emplace(stamp, std::move(png));
}

void KittiWriter::write_per_pixel(std::size_t index, const Png& png) {
  std::ostringstream name;
  name << seq_dir_.substr(root().size() + 1) << (png.first ? "/depth_0/" : "/seg_0/") << std::setw(6)
       << std::setfill('0') << index << ".png";
  write_file_logged(root(), name.str(), png.second);
  ++(png.first ? counts_.depth : counts_.segmentation);
}

void KittiWriter::write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& /*X_WB*/) {
  // Line i belongs to image i: a pose is written only when it is the next image's, so the file
  // stays a valid prefix if an image never gets its ground truth.
  if (counts_.poses >= image_stamps_.size() || stamp != image_stamps_[counts_.poses]) {
    ++unpaired_poses_;
    return;
  }
  if (!have_first_) {
    X_C0W_ = X_WC.inverse();
    have_first_ = true;
  }
  const Eigen::Matrix4d T = (X_C0W_ * X_WC).matrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) poses_ << T(r, c) << (r == 2 && c == 3 ? '\n' : ' ');
  poses_.flush();
  ++counts_.poses;
}

void KittiWriter::close() {
  if (closed_) return;
  closed_ = true;
  if (times_.is_open()) times_.close();
  if (poses_.is_open()) poses_.close();
}

std::vector<std::string> KittiWriter::warnings() const {
  std::vector<std::string> w;
  if (counts_.poses < image_stamps_.size())
    w.push_back(root_ + "/poses: " + std::to_string(image_stamps_.size() - counts_.poses) + " of " +
                std::to_string(image_stamps_.size()) + " images have no ground-truth pose (the file ends at image " +
                std::to_string(counts_.poses) + ")");
  if (unpaired_poses_ > 0)
    w.push_back(root_ + "/poses: " + std::to_string(unpaired_poses_) +
                " poses were not the next image's and were not written");
  if (!pending_.empty())
    w.push_back(seq_dir_ + ": " + std::to_string(pending_.size()) +
                " depth/segmentation images never got their colour image (no index) and were not written");
  if (distorted_)
    w.push_back(seq_dir_ +
                "/calib.txt: the camera has lens distortion, which KITTI's rectified layout cannot store: record "
                "an undistorted camera");
  return w;
}

}  // namespace unav::datagen

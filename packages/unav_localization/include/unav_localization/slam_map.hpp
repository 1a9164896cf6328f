// The map of the monocular SLAM: keyframes (pose, ORB features, bag of words), map points
// (position, representative descriptor, observations), the covisibility graph and the spanning
// tree. Poses are T_cw: world -> camera optical frame (z forward, x right, y down); the world is
// the first keyframe's camera frame at the scale chosen at initialisation.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "unav_localization/bow_vocabulary.hpp"

namespace unav::localization {

/// Pinhole camera of rectified pixel coordinates (features are undistorted on extraction).
struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  static PinholeCamera FromK(const Eigen::Matrix3d& K, int image_width, int image_height) {
    return {K(0, 0), K(1, 1), K(0, 2), K(1, 2), image_width, image_height};
  }
  Eigen::Vector2d Project(const Eigen::Vector3d& p_c) const {
    return {fx * p_c.x() / p_c.z() + cx, fy * p_c.y() / p_c.z() + cy};
  }
  Eigen::Vector3d Unproject(const Eigen::Vector2d& uv) const { return {(uv.x() - cx) / fx, (uv.y() - cy) / fy, 1.0}; }
  Eigen::Matrix3d K() const {
    Eigen::Matrix3d k;
    k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    return k;
  }
};

/// Features of one image, bucketed in a grid for radius searches.
struct Features {
  std::vector<cv::KeyPoint> keypoints;  ///< as detected (distorted) pixels, octave = pyramid level
  std::vector<Eigen::Vector2d> un;      ///< undistorted pixels
  cv::Mat descriptors;                  ///< CV_8U, 32 bytes per row
  BowVector bow;
  FeatureVector feature_vector;
  int grid_cols = 0, grid_rows = 0;
  double cell_px = 16.0;
  std::vector<std::vector<int>> grid;

  size_t size() const { return keypoints.size(); }
  const uint8_t* desc(int i) const { return descriptors.ptr<uint8_t>(i); }
  void BuildGrid(int width, int height, double cell);
  /// Feature indices within `radius` px of uv, on pyramid levels [min_level, max_level] (-1: any).
  std::vector<int> InArea(const Eigen::Vector2d& uv, double radius, int min_level = -1, int max_level = -1) const;
};

struct MapPoint {
  int id = -1;
  Eigen::Vector3d X_w = Eigen::Vector3d::Zero();
  cv::Mat descriptor;                                 ///< representative: least median distance to its observations
  std::map<int, int> obs;                             ///< keyframe id -> feature index
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< mean viewing direction (world)
  double min_distance = 0, max_distance = 0;          ///< scale-invariance range [map units]
  int first_kf = -1;                                  ///< keyframe that created it
  int ref_kf = -1;                                    ///< keyframe whose correction moves it
  int visible = 1, found = 1;                         ///< times predicted in view / times matched (tracking)
  int last_seen_frame = -1;                           ///< tracking bookkeeping
  bool bad = false;
  double FoundRatio() const { return static_cast<double>(found) / visible; }
};

struct KeyFrame {
  int id = -1;
  int frame_index = -1;  ///< index of the tracked frame it was made from
  double stamp = 0.0;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  Features f;
  std::vector<int> points;          ///< feature index -> map point id (-1: none)
  std::map<int, int> covisibility;  ///< keyframe id -> shared map points (>= threshold)
  int parent = -1;                  ///< spanning tree
  std::set<int> children, loop_edges;
  bool bad = false;
  Eigen::Vector3d Center() const { return T_cw.inverse().translation(); }
  std::vector<int> BestCovisible(size_t n) const;  ///< by weight, strongest first
};

struct Map {
  std::vector<std::unique_ptr<KeyFrame>> keyframes;  ///< index = id
  std::vector<std::unique_ptr<MapPoint>> points;     ///< index = id
  KeyFrame& kf(int id) { return *keyframes[static_cast<size_t>(id)]; }
  const KeyFrame& kf(int id) const { return *keyframes[static_cast<size_t>(id)]; }
  MapPoint& mp(int id) { return *points[static_cast<size_t>(id)]; }
  const MapPoint& mp(int id) const { return *points[static_cast<size_t>(id)]; }
  int AddPoint(const Eigen::Vector3d& X_w, int kf_id);
  void AddObservation(int point, int kf_id, int feature);
  void EraseObservation(int point, int kf_id);
  void ErasePoint(int point);
  /// Merges `from` into `into` (observations, tracking counts); `from` becomes bad.
  void Replace(int from, int into);
  /// Recomputes a point's representative descriptor, normal and distance range.
  void UpdatePoint(int point, const std::vector<double>& level_scales);
  /// Recomputes a keyframe's covisibility (and its neighbours' entries); sets the spanning-tree
  /// parent of a new keyframe.
  void UpdateConnections(int kf_id, int min_weight = 15);
  int GoodPoints() const;
  int GoodKeyFrames() const;
  double MedianDepth(int kf_id) const;
};

}  // namespace unav::localization

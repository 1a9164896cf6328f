// Between Eigen poses and OpenCV's PnP rotation vector + translation (solvePnP*: the pose maps
// the object points into the camera frame). Internal to unav_localization.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace unav::localization::detail {

/// rvec, tvec (3 x 1, CV_64F) of T: an initial guess for solvePnP* (useExtrinsicGuess).
inline void ToRvecTvec(const Eigen::Isometry3d& T, cv::Mat* rvec, cv::Mat* tvec) {
  cv::Mat R(3, 3, CV_64F);
  *tvec = cv::Mat(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R.at<double>(r, c) = T.linear()(r, c);
    tvec->at<double>(r) = T.translation()[r];
  }
  cv::Rodrigues(R, *rvec);
}

/// The pose of a solvePnP* result (rvec, tvec: 3 x 1, CV_64F).
inline Eigen::Isometry3d FromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = R.at<double>(r, c);
    T.translation()[r] = tvec.at<double>(r);
  }
  return T;
}

}  // namespace unav::localization::detail

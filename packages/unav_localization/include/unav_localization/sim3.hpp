// Similarity transforms Sim(3): x' = s R x + t. Used for monocular maps, whose scale is not
// observable and drifts, and for loop corrections.
#pragma once

#include <Eigen/Geometry>

#include "unav_common/sim3.hpp"

namespace unav::localization {

/// The workspace's one Sim(3) (unav_common/sim3.hpp).
using Sim3 = unav::common::Sim3;

/// Closed-form similarity (Umeyama 1991) mapping `from` onto `to` (3xN, N >= 3): to ~ S * from.
/// Returns false when the points are degenerate (collinear, coincident).
bool EstimateSim3(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool fix_scale, Sim3* S);

}  // namespace unav::localization

// Frames and poses of the scene: the common floor's (unav_common/frames.hpp), named here.
//
// World frame `world_ned`: x north, y east, z down (metres; z = depth below the surface).
// Body frame `base_link_frd`: x forward, y right, z down.
// Camera optical frame `<name>_optical`: z forward (optical axis), x right, y down.
// Poses follow Drake's monogram notation: X_WB is the pose of frame B in frame W, so that
// p_W = X_WB * p_B.
#pragma once

#include "unav_common/frames.hpp"

namespace unav::scene {

using unav::common::Pose;
using unav::common::pose_from_xyz_rpy;
using unav::common::R_camera_body_to_optical;
using unav::common::rotation_from_rpy;

}  // namespace unav::scene

// How well a trajectory follows a pipeline (the pipe-following figures of merit): the
// horizontal cross-track error e_p along it and how much of the pipe was followed before the
// pipe was lost (e_p beyond `loss_distance_m`, the environment's termination).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "unav_scene/world.hpp"

namespace unav::scene {

struct PipeTracking {
  int samples = 0;        ///< positions counted (up to the loss, included)
  double mean_e_p_m = 0;  ///< mean horizontal distance to the centre line
  double max_e_p_m = 0;
  double rms_e_p_m = 0;
  double followed_m = 0;  ///< largest arc length reached before the loss
  double pipe_length_m = 0;
  double followed_fraction = 0;  ///< followed_m / pipe_length_m
  bool lost = false;             ///< e_p exceeded loss_distance_m before the end was reached
  bool completed = false;        ///< reached within end_margin_m of the end (counting stops)
  double lost_at_index = -1;     ///< index of the first position beyond it (-1: never)
};

/// Positions in world NED, in time order, against the world's first pipeline. Counting stops at
/// the first position farther than loss_distance_m (horizontally) from the centre line (lost),
/// or at the first one within end_margin_m of the pipe's end (completed), as the environment's
/// termination and truncation do.
PipeTracking track_pipe(const World& world, const std::vector<Eigen::Vector3d>& positions_W,
                        double loss_distance_m = 2.5, double end_margin_m = 1.0);

}  // namespace unav::scene

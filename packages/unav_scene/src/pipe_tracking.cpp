#include "unav_scene/pipe_tracking.hpp"

#include <algorithm>
#include <cmath>

namespace unav::scene {

PipeTracking track_pipe(const World& world, const std::vector<Eigen::Vector3d>& positions_W, double loss_distance_m,
                        double end_margin_m) {
  PipeTracking t;
  if (world.pipelines.empty()) return t;
  t.pipe_length_m = world.pipelines.front().length_m();
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < positions_W.size(); ++i) {
    const PipeQuery q = nearest_pipe_point(world, positions_W[i], true);
    const double e = q.horizontal_distance_m;
    ++t.samples;
    sum += e;
    sum2 += e * e;
    t.max_e_p_m = std::max(t.max_e_p_m, e);
    if (!(e <= loss_distance_m)) {
      t.lost = true;
      t.lost_at_index = static_cast<double>(i);
      break;
    }
    t.followed_m = std::max(t.followed_m, q.arc_length_m);
    if (q.arc_length_m >= t.pipe_length_m - end_margin_m) {
      t.completed = true;
      break;
    }
  }
  if (t.samples > 0) {
    t.mean_e_p_m = sum / t.samples;
    t.rms_e_p_m = std::sqrt(sum2 / t.samples);
  }
  t.followed_fraction = t.pipe_length_m > 0 ? t.followed_m / t.pipe_length_m : 0.0;
  return t;
}

}  // namespace unav::scene

// The trajectory readers of `unav eval` (TUM, KITTI, EuRoC csv) on arbitrary text: must give
// TrajectoryError naming file, line and column.
#include "fuzz_common.hpp"
#include "unav_evaluation/trajectory.hpp"

namespace ev = unav::evaluation;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = unav::fuzz::write_input(data, size, ".traj");
  for (auto f : {ev::TrajectoryFormat::kTum, ev::TrajectoryFormat::kKitti, ev::TrajectoryFormat::kEuroc}) {
    try {
      const ev::Trajectory t = ev::read_trajectory(path, f);
      if (t.size() > 1) (void)ev::associate(t, t, 0.01);
    } catch (const ev::TrajectoryError&) {
    }
  }
  return 0;
}

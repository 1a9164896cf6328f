// unav_launch_run FILE [NAME:=VALUE ...]: loads a launch file and supervises its nodes.
#include <iostream>

#include "unav_launch/launch_description.hpp"
#include "unav_launch/supervisor.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " FILE.launch.yaml [NAME:=VALUE ...]\n";
    return 2;
  }
  try {
    const auto overrides = unav::launch::parse_launch_arguments({argv + 2, argv + argc});
    return unav::launch::run(unav::launch::load_launch_file(argv[1], overrides));
  } catch (const unav::launch::LaunchError& e) {
    std::cerr << "[ERROR] [launch]: " << e.what() << '\n';
    return 2;
  }
}

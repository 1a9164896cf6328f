// Writes the procedural rock used by worlds/*/meshes/rock.obj:
//   unav_make_rock OUT.obj [seed] [rx ry rz]
#include <cstdlib>
#include <iostream>

#include "unav_scene/scene_geometry.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: unav_make_rock OUT.obj [seed] [rx ry rz]\n";
    return 2;
  }
  const auto seed = static_cast<std::uint32_t>(argc > 2 ? std::atoi(argv[2]) : 42);
  Eigen::Vector3d radii(0.6, 0.45, 0.35);
  if (argc > 5) radii = {std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])};
  try {
    unav::scene::write_obj(unav::scene::make_rock_mesh(seed, radii, 2), argv[1]);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

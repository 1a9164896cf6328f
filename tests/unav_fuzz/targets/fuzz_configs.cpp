// The config loaders (vehicle, water, cameras, world, sonars) on arbitrary YAML: must give ConfigError
// (file, key, value, rule), never a crash. The first byte picks the loader.
#include <stdexcept>

#include "fuzz_common.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/sonar.hpp"
#include "unav_scene/water.hpp"
#include "unav_scene/world.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string path = unav::fuzz::write_input(data + 1, size - 1, ".yaml");
  try {
    switch (data[0] % 5) {
      case 0:
        (void)unav::physics::load_vehicle(path);
        break;
      case 1:
        (void)unav::scene::load_water_file(path);
        break;
      case 2:
        (void)unav::scene::load_cameras(path);
        break;
      case 3:
        (void)unav::scene::load_world(path);
        break;
      default:
        (void)unav::scene::load_sonars(path);
        break;
    }
  } catch (const std::runtime_error&) {  // ConfigError, and yaml-cpp's parse errors
  } catch (const std::logic_error&) {    // yaml-cpp's InvalidNode / BadConversion
  }
  return 0;
}

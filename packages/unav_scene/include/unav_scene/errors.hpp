// Scene configuration errors (world/water/camera YAML, missing mesh file, bad value): the
// workspace's one ConfigError, whose messages name the file and the key (STYLE.md rule 7).
#pragma once

#include "unav_common/errors.hpp"

namespace unav::scene {

using ConfigError = unav::ConfigError;

}  // namespace unav::scene

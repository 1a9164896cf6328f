// Finding installed packages and their executables, the way ROS 2 (ament_index) does: the
// common floor's implementation (unav_common/resources.hpp), named in the launch namespace for
// the launch library and the CLI.
#pragma once

#include "unav_common/resources.hpp"

namespace unav::launch {

using unav::common::find_executable;
using unav::common::find_package_prefix;
using unav::common::find_package_share;
using unav::common::package_search_prefixes;

}  // namespace unav::launch

// Finding installed packages and their executables, the way ROS 2 (ament_index) does.
//
// A package PKG is installed under prefix P when the folder P/share/PKG exists; its
// executables are the executable files P/lib/PKG/EXEC. Prefixes come from the environment:
// AMENT_PREFIX_PATH and CMAKE_PREFIX_PATH list prefixes, COLCON_PREFIX_PATH lists install
// roots R, each searched as R/PKG (isolated layout) and R (merged layout).
//
// Forwards to unav_common/resources.hpp (unav::common), which holds the implementation and
// also finds data files (unav::common::find_resource).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace unav::launch {

/// Candidate prefixes for `package`, in search order, without duplicates: the entries of
/// AMENT_PREFIX_PATH, then CMAKE_PREFIX_PATH, then ROOT/package and ROOT for each ROOT of
/// COLCON_PREFIX_PATH. The folders need not exist.
std::vector<std::string> package_search_prefixes(const std::string& package);

/// First prefix P of package_search_prefixes(package) with a folder P/share/package.
std::optional<std::string> find_package_prefix(const std::string& package);

/// find_package_prefix(package) + "/share/" + package.
std::optional<std::string> find_package_share(const std::string& package);

/// Path of the executable file P/lib/package/executable, for the first prefix P (in search
/// order) holding share/package and that file. When `searched_dirs` is given, it receives
/// every P/lib/package folder looked at (empty when the package is not installed at all).
std::optional<std::string> find_executable(const std::string& package,
                                           const std::string& executable,
                                           std::vector<std::string>* searched_dirs = nullptr);

}  // namespace unav::launch

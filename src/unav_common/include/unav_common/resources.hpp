// Finding installed packages, executables and the workspace's data files (config/, worlds/,
// launch_scripts/), the way ROS 2 (ament_index) does.
//
// A package PKG is installed under prefix P when the folder P/share/PKG exists; its
// executables are the executable files P/lib/PKG/EXEC. Prefixes come from the environment:
// AMENT_PREFIX_PATH and CMAKE_PREFIX_PATH list prefixes, COLCON_PREFIX_PATH lists install
// roots R, each searched as R/PKG (isolated layout) and R (merged layout).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace unav::common {

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
std::optional<std::string> find_executable(const std::string& package, const std::string& executable,
                                           std::vector<std::string>* searched_dirs = nullptr);

/// The package whose share folder holds the workspace's config/, worlds/ and launch_scripts/.
inline constexpr const char* kResourcePackage = "unav_resources";

/// Roots that data files are looked up under, in order: each entry of UNAV_RESOURCE_PATH
/// (colon-separated), then the share folder of unav_resources when it is installed.
std::vector<std::string> resource_roots();

/// Absolute path of a data file or folder such as "config/controllers/mpc.yaml",
/// "worlds/pipe_inspection/world.yaml" or "config": an absolute `path` as it is when it
/// exists; otherwise ROOT/path for the first root of resource_roots() where it exists.
/// Empty when not found (for callers with a fallback, e.g. a parameter default of "").
std::optional<std::string> try_find_resource(const std::string& path);

/// try_find_resource(path) or "": a node parameter's default (empty when unav_resources is not
/// installed; the node then asks for the parameter).
std::string resource_or_empty(const std::string& path);

/// try_find_resource(path), or throws unav::ConfigError naming `path` and every place looked
/// at (including "unav_resources is not installed" when it is not).
std::string find_resource(const std::string& path);

}  // namespace unav::common

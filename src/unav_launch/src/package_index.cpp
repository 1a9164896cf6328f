// Thin forwards: the package index lives in unav_common (unav_common/resources.hpp).
#include "unav_launch/package_index.hpp"

#include "unav_common/resources.hpp"

namespace unav::launch {

std::vector<std::string> package_search_prefixes(const std::string& package) {
  return common::package_search_prefixes(package);
}

std::optional<std::string> find_package_prefix(const std::string& package) {
  return common::find_package_prefix(package);
}

std::optional<std::string> find_package_share(const std::string& package) {
  return common::find_package_share(package);
}

std::optional<std::string> find_executable(const std::string& package, const std::string& executable,
                                           std::vector<std::string>* searched_dirs) {
  return common::find_executable(package, executable, searched_dirs);
}

}  // namespace unav::launch

# unav_package(): call right after project() in every C++ package of the workspace.
# - C++17, no compiler extensions, position-independent code
# - warnings as the project wants them (-Wall -Wextra -Wpedantic ...), -Werror with UNAV_WERROR=ON
# - installed executables find workspace libraries (RPATH from link path)
# - ccache when present
# - RelWithDebInfo with line-table debug info (-g1: backtraces and profilers keep file:line; a
#   debugger sees no local variables). Full -g with -DUNAV_FULL_DEBUG_INFO=ON. -g1 compiles the
#   Eigen/OpenCV/Ceres-heavy units ~25-35 % faster and writes ~8x smaller objects.
# - BUILD_TESTING (default ON) and GoogleTest found once
macro(unav_package)
  if(NOT CMAKE_CXX_STANDARD)
    set(CMAKE_CXX_STANDARD 17)
  endif()
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  set(CMAKE_CXX_EXTENSIONS OFF)
  set(CMAKE_POSITION_INDEPENDENT_CODE ON)
  if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
    set(CMAKE_BUILD_TYPE RelWithDebInfo)
  endif()
  option(UNAV_FULL_DEBUG_INFO "Full -g debug info in RelWithDebInfo builds (default: -g1)" OFF)
  if(NOT UNAV_FULL_DEBUG_INFO AND CMAKE_CXX_FLAGS_RELWITHDEBINFO STREQUAL "-O2 -g -DNDEBUG")
    set(CMAKE_CXX_FLAGS_RELWITHDEBINFO "-O2 -g1 -DNDEBUG")
  endif()
  set(CMAKE_INSTALL_RPATH_USE_LINK_PATH ON)
  set(CMAKE_INSTALL_RPATH "${CMAKE_INSTALL_PREFIX}/lib")
  set(CMAKE_EXPORT_COMPILE_COMMANDS ON)
  find_program(UNAV_CCACHE ccache)
  if(UNAV_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
    set(CMAKE_CXX_COMPILER_LAUNCHER ${UNAV_CCACHE})
  endif()
  option(UNAV_WERROR "Treat warnings as errors" OFF)
  add_compile_options(-Wall -Wextra -Wpedantic -Wshadow=local -Wnon-virtual-dtor)
  if(UNAV_WERROR)
    add_compile_options(-Werror)
  endif()
  include(GNUInstallDirs)
  # The repository root (worlds/, config/, test data; every package is two folders below it) and
  # the project's Python venv (scripts/install_deps.sh makes it; UNAV_VENV overrides).
  get_filename_component(UNAV_REPO_ROOT "${CMAKE_CURRENT_SOURCE_DIR}/../.." ABSOLUTE)
  if(DEFINED ENV{UNAV_VENV})
    set(UNAV_VENV "$ENV{UNAV_VENV}")
  else()
    set(UNAV_VENV "${UNAV_REPO_ROOT}/.venv")
  endif()
  option(BUILD_TESTING "Build the tests" ON)
  # Benchmarks come with the tests (README command 2), not with the demo (command 1, which builds
  # with -DBUILD_TESTING=OFF); -DUNAV_BUILD_BENCHMARKS=ON builds them without the tests.
  if(NOT DEFINED UNAV_BUILD_BENCHMARKS)
    set(UNAV_BUILD_BENCHMARKS ${BUILD_TESTING})
  endif()
  if(BUILD_TESTING)
    enable_testing()
    find_package(GTest REQUIRED)
    include(GoogleTest)
  endif()
endmacro()

# unav_add_library(NAME [SHARED|STATIC] SOURCES ... [PUBLIC libs...] [PRIVATE libs...]): a library
# of the package with include/ as its public headers (build and install trees) and the alias
# <PROJECT_NAME>::<NAME>, the name its users see after find_package(); install it with
# unav_install_library().
function(unav_add_library name)
  cmake_parse_arguments(ARG "SHARED;STATIC" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  set(_type "")
  if(ARG_SHARED)
    set(_type SHARED)
  elseif(ARG_STATIC)
    set(_type STATIC)
  endif()
  add_library(${name} ${_type} ${ARG_SOURCES})
  add_library(${PROJECT_NAME}::${name} ALIAS ${name})
  target_include_directories(${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
  if(ARG_PUBLIC)
    target_link_libraries(${name} PUBLIC ${ARG_PUBLIC})
  endif()
  if(ARG_PRIVATE)
    target_link_libraries(${name} PRIVATE ${ARG_PRIVATE})
  endif()
endfunction()

# unav_add_node(LIB DIR dir SOURCES ... LINKS ... EXECUTABLES name=main.cpp ...): a package's thin
# DDS adapter: a static library LIB (the in-process node tests link it; its headers in DIR) and
# its executables, each built from DIR/<main>, linked to LIB and installed in lib/<PROJECT_NAME>
# (where `unav launch` and `unav run` find them).
function(unav_add_node lib)
  cmake_parse_arguments(ARG "" "DIR" "SOURCES;LINKS;EXECUTABLES" ${ARGN})
  add_library(${lib} STATIC ${ARG_SOURCES})
  target_include_directories(${lib} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/${ARG_DIR})
  target_link_libraries(${lib} PUBLIC ${ARG_LINKS})
  foreach(_exe IN LISTS ARG_EXECUTABLES)
    string(REPLACE "=" ";" _kv "${_exe}")
    list(GET _kv 0 _name)
    list(GET _kv 1 _main)
    add_executable(${_name} ${ARG_DIR}/${_main})
    target_link_libraries(${_name} PRIVATE ${lib})
    install(TARGETS ${_name} DESTINATION lib/${PROJECT_NAME})
  endforeach()
endfunction()

# unav_add_gtest(NAME SOURCES... LIBS ... [TIMEOUT s] [ENV ...] [FIXTURES ...] [REPO]): a GoogleTest
# executable registered with CTest. Each test case becomes its own CTest test
# (gtest_discover_tests), with a timeout. REPO: the test reads the repository's data:
# UNAV_REPO_ROOT is defined (a string) and the repository is a resource root (UNAV_RESOURCE_PATH),
# so a scenario's files resolve. FIXTURES: CTest fixtures every case requires (FIXTURES_REQUIRED:
# ctest runs their setup tests first).
function(unav_add_gtest name)
  cmake_parse_arguments(ARG "REPO" "TIMEOUT" "SOURCES;LIBS;ENV;FIXTURES" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  if(ARG_REPO)
    target_compile_definitions(${name} PRIVATE UNAV_REPO_ROOT="${UNAV_REPO_ROOT}")
    list(APPEND ARG_ENV "UNAV_RESOURCE_PATH=${UNAV_REPO_ROOT}")
  endif()
  set(_fixtures)
  if(ARG_FIXTURES)
    set(_fixtures FIXTURES_REQUIRED "${ARG_FIXTURES}")
  endif()
  # An empty ENVIRONMENT would take the next property's name as its value.
  if(ARG_ENV)
    gtest_discover_tests(${name}
      DISCOVERY_TIMEOUT 60
      PROPERTIES TIMEOUT ${ARG_TIMEOUT} ENVIRONMENT "${ARG_ENV}" ${_fixtures})
  else()
    gtest_discover_tests(${name}
      DISCOVERY_TIMEOUT 60
      PROPERTIES TIMEOUT ${ARG_TIMEOUT} ${_fixtures})
  endif()
endfunction()

# unav_add_pytest(NAME FILE [TIMEOUT s] [ENV ...]): a pytest file run by the project's venv, with
# the repository as a resource root.
function(unav_add_pytest name)
  cmake_parse_arguments(ARG "" "FILE;TIMEOUT" "ENV" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_test(NAME ${name} COMMAND ${UNAV_VENV}/bin/python -m pytest -q -p no:cacheprovider ${ARG_FILE})
  set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "UNAV_RESOURCE_PATH=${UNAV_REPO_ROOT};${ARG_ENV}")
endfunction()

# unav_forbid_links(target REASON text PATTERN regex): fail the configure step if `target` links
# a library matching `regex` (layering rules checked where the link is made).
function(unav_forbid_links target)
  cmake_parse_arguments(ARG "" "REASON;PATTERN" "" ${ARGN})
  get_target_property(_libs ${target} LINK_LIBRARIES)
  foreach(_l IN LISTS _libs)
    if(_l MATCHES "${ARG_PATTERN}")
      message(FATAL_ERROR "${target} must not link ${_l}: ${ARG_REASON}")
    endif()
  endforeach()
endfunction()

# unav_forbid_dds(target): a core library stays free of middleware (DESIGN.md section 1).
function(unav_forbid_dds target)
  unav_forbid_links(${target} PATTERN "fastrtps|fastcdr|fastdds|_msgs|unav_runtime"
    REASON "it is a core library (DDS-free, DESIGN.md section 1)")
endfunction()

# unav_forbid_gl(target): only the renderer draws; the scene, physics, control, localization,
# evaluation and datagen cores run without a GPU stack (DESIGN.md section 8).
function(unav_forbid_gl target)
  unav_forbid_links(${target} PATTERN "EPOXY|epoxy|OpenGL|EGL|GLESv|unav_renderer::unav_renderer"
    REASON "only the renderer uses OpenGL (DESIGN.md section 8)")
endfunction()

# unav_install_library(TARGETS t... [DEPENDENCIES dep...] [EXTRA code]): the one export block of a library
# package. Installs the targets (lib/, bin/), the headers of include/, an export set
# <PROJECT_NAME>Targets in namespace <PROJECT_NAME>:: and a <PROJECT_NAME>Config.cmake that
# calls find_dependency() for each DEPENDENCIES entry (e.g. "Eigen3 3.3 NO_MODULE",
# "unav_common", "OpenCV COMPONENTS core imgcodecs"; a static library also needs its private
# dependencies there), plus package.xml. Consumers: find_package(<pkg>) + <pkg>::<target>.
function(unav_install_library)
  cmake_parse_arguments(ARG "" "EXTRA" "TARGETS;DEPENDENCIES" ${ARGN})
  install(TARGETS ${ARG_TARGETS} EXPORT ${PROJECT_NAME}Targets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY include/ DESTINATION include)
  install(EXPORT ${PROJECT_NAME}Targets NAMESPACE ${PROJECT_NAME}:: DESTINATION share/${PROJECT_NAME}/cmake)
  set(_config "include(CMakeFindDependencyMacro)\n")
  foreach(_dep IN LISTS ARG_DEPENDENCIES)
    string(APPEND _config "find_dependency(${_dep})\n")
  endforeach()
  if(ARG_EXTRA)
    string(APPEND _config "${ARG_EXTRA}\n")  # raw CMake, e.g. pkg_check_modules() for an imported target
  endif()
  string(APPEND _config "include(\"\${CMAKE_CURRENT_LIST_DIR}/${PROJECT_NAME}Targets.cmake\")\n")
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/${PROJECT_NAME}Config.cmake "${_config}")
  install(FILES ${CMAKE_CURRENT_BINARY_DIR}/${PROJECT_NAME}Config.cmake DESTINATION share/${PROJECT_NAME}/cmake)
  install(FILES package.xml DESTINATION share/${PROJECT_NAME})
endfunction()

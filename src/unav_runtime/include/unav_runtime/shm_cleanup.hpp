// Leftover Fast DDS data-sharing segments: a writer that dies without closing (SIGKILL, a crash)
// leaves its pool in /dev/shm (`fast_datasharing_<guid prefix>_<entity id>`, ~20 MB for an image
// topic) until reboot; a sweep that kills renderers leaks without bound. Fast DDS 2.9 has no
// clean-up for these (`fastdds shm clean` handles the shared-memory transport's ports only).
//
// A segment's name carries its writer's GUID prefix, which Fast DDS builds as vendor (2 bytes),
// host id (2), the low 16 bits of the writer's process id (2), a random number (2) and the
// participant id (4) (Fast-DDS src/cpp/rtps/common/GuidUtils.hpp). A segment is dead when no live
// process on this host has a pid with those low 16 bits: only then is it removed (shm_unlink;
// a reader that still maps it keeps its memory). A live process that only shares the low bits
// keeps a dead segment alive until it exits (conservative: never a live writer's pool). With
// `host_id`, segments of other hosts' ids (another container sharing /dev/shm) are left alone.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace unav::shm {

struct Segment {
  std::string name;  ///< file name under the folder
  std::uint64_t bytes = 0;
  std::uint16_t pid16 = 0;  ///< the writer's pid, low 16 bits
  std::array<std::uint8_t, 2> host{};
  bool dead = false;  ///< no live process has pid16
};

struct CleanReport {
  std::vector<Segment> segments;  ///< every data-sharing segment found
  std::uint64_t removed_bytes = 0;
  int removed = 0;
  std::vector<std::string> errors;  ///< segments that could not be removed (name: reason)
};

/// Parses `fast_datasharing_01.0f.HH.HH.PP.PP.RR.RR.II.II.II.II_E.E.E.E`; nullopt for any other name.
std::optional<Segment> parse_data_sharing_name(const std::string& name);

/// The low 16 bits of every live process's pid (from /proc).
std::vector<bool> live_pid16();

/// Lists the data-sharing segments of `dir` and, unless `dry_run`, removes the dead ones (of
/// `host_id` only, when given).
CleanReport clean_data_sharing(const std::string& dir = "/dev/shm", bool dry_run = false,
                               std::optional<std::array<std::uint8_t, 2>> host_id = std::nullopt);

}  // namespace unav::shm

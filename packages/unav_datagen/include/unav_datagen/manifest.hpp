// manifest.json of a recorded sequence: what it is, how it was made, and a checksum of every file,
// so a dataset can be verified and compared (two runs of the same seed must give the same
// checksums). Written when the recorder closes (also on Ctrl-C); no wall-clock time in it, so a
// reproduced sequence has a byte-identical manifest.
//
//   {
//     "format": "tum" | "euroc" | "kitti",
//     "software": {"name": "unav-sim", "commit": "<git commit of the build>"},
//     "camera": {"name", "width", "height", "fx", "fy", "cx", "cy", "distortion_model": "plumb_bob",
//                "distortion", "parent_frame", "frame", "mount_known",
//                "mount_xyz_m", "mount_quaternion_xyzw"},
//     "source": {...},                      // free-form key -> string (world file, water, ...)
//     "randomization": {...},               // unav datagen: the resolved sample (seed, every value)
//     "counts": {"images", "depth", "segmentation", "poses", "imu"},
//     "labels": {"0": "water", ...},        // segmentation class ids
//     "depth": {"png": "uint16", "units_per_metre": 5000 | 1000, "zero": "no return or out of range"},
//     "sonar": {...},                       // unav datagen with output.sonar: geometry, pings (extra_json)
//     "files": [{"path": "rgb/0.000000.png", "bytes": 1234, "sha256": "..."}, ...]   // sorted by path
//   }
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "unav_datagen/dataset_writer.hpp"

namespace unav::datagen {

struct ManifestInput {
  std::string format;
  std::string camera;  ///< camera name; its frame is <camera>_optical
  CameraIntrinsics intrinsics;
  bool mount_known = false;
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();  ///< optical frame in the parent frame
  std::string parent_frame = "base_link_frd";
  std::map<std::string, std::string> source;        ///< e.g. {"world": path}
  std::vector<std::pair<int, std::string>> labels;  ///< segmentation class id -> name
  /// The resolved randomization sample (YAML text; "" = none), written as "randomization".
  std::string randomization_yaml;
  /// More files or folders under the root (relative) to list with checksums, e.g. {"world"}.
  std::vector<std::string> extra_entries;
  /// More top-level entries: key -> JSON text (e.g. "sonar": its geometry and files).
  std::map<std::string, std::string> extra_json;
};

/// Lowercase hex SHA-256 of a file's bytes. Throws DatasetError naming the file it cannot read.
std::string sha256_file(const std::string& path);
/// Lowercase hex SHA-256 of a byte string.
std::string sha256_bytes(const std::string& bytes);
/// Writes `bytes` to <root>/<relative> and appends its size and SHA-256 to <root>/.sha256, the
/// digest log that write_manifest reads instead of hashing the file again: an hour of frames
/// (tens of thousands of PNGs) is then listed in the manifest at once when the recorder stops,
/// not after a minute of hashing that a launch's shutdown would cut short. Throws DatasetError
/// naming the file.
void write_file_logged(const std::string& root, const std::string& relative, const std::vector<std::uint8_t>& bytes);
/// The git commit the library was built from ("unknown" outside a git checkout).
std::string software_commit();

/// Writes <writer.root()>/manifest.json from the writer's counts and layout and every file under
/// the root (manifest.json itself excluded), atomically (a temporary file renamed into place).
/// Throws DatasetError naming the path on an I/O error.
void write_manifest(const SequenceWriter& writer, const ManifestInput& input);

}  // namespace unav::datagen

// Seabed models: the depth of the sea floor under a horizontal position (NED).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "unav_physics/types.hpp"

namespace unav::physics {

/// The sea floor as a height field z_seabed(x, y) (NED: a depth, m, positive down).
class Seabed {
 public:
  virtual ~Seabed() = default;
  /// Depth of the seabed below the surface at north x_N, east y_E (m); called per dynamics stage.
  virtual double depth_at(double x_N, double y_E) const = 0;
  /// A depth the seabed is nowhere shallower than (m): what a ray need not be followed above;
  /// -infinity when unknown.
  virtual double shallowest_depth() const { return -std::numeric_limits<double>::infinity(); }
};

class FlatSeabed final : public Seabed {
 public:
  explicit FlatSeabed(double depth_m);
  double depth_at(double, double) const override { return depth_m_; }
  double shallowest_depth() const override { return depth_m_; }

 private:
  double depth_m_;
};

/// A regular grid of depths with bilinear interpolation; positions outside the grid take the
/// nearest edge value. depths_m[i][j] lies at x_N = origin_N + i * resolution,
/// y_E = origin_E + j * resolution (rows run north, columns east).
class GridSeabed final : public Seabed {
 public:
  /// Throws ConfigError if the grid is empty, ragged, non-finite or the resolution is <= 0.
  GridSeabed(double origin_N, double origin_E, double resolution_m, std::vector<std::vector<double>> depths_m);
  double depth_at(double x_N, double y_E) const override;
  double shallowest_depth() const override { return shallowest_m_; }  // bilinear: within the nodes' range
  int rows() const { return rows_; }
  int cols() const { return cols_; }

 private:
  double origin_N_, origin_E_, resolution_m_;
  int rows_ = 0, cols_ = 0;
  std::vector<double> depths_m_;  // row-major
  double shallowest_m_ = 0.0;
};

/// Builds a seabed from a YAML map (example: test/data/seabed_grid.yaml):
///   type: flat, depth: 30.0                                    # m
///   type: grid, origin_N: 0, origin_E: 0, resolution: 1.0, depths: [[...], ...]   # m
///   type: pgm, file: floor.pgm (relative to the YAML), origin_N, origin_E, resolution,
///         depth_white, depth_black   # m; pixel value v maps linearly: 0 -> black, max -> white
/// `source` names the file for error messages, `key` the map's path ("seabed").
std::unique_ptr<Seabed> make_seabed(const YAML::Node& node, const std::string& source,
                                    const std::string& key = "seabed");
/// Loads a YAML file whose top level is the seabed map (or has a `seabed:` key).
std::unique_ptr<Seabed> load_seabed(const std::string& yaml_path);

}  // namespace unav::physics

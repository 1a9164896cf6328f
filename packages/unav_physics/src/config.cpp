// YAML loading and validation of vehicles, currents, seabeds and environments. Every error
// names the source file, the key path, the value and the rule it broke.
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "unav_physics/current.hpp"
#include "unav_physics/seabed.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::physics {

namespace {

std::string flow(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  YAML::Emitter e;
  e << YAML::Flow << n;
  return e.c_str();
}

template <typename Derived>
std::string text(const Eigen::MatrixBase<Derived>& m) {
  std::ostringstream os;
  os << "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if (i) os << ", ";
    if (m.cols() == 1) {
      os << m(i, 0);
      continue;
    }
    os << "[";
    for (Eigen::Index j = 0; j < m.cols(); ++j) os << (j ? ", " : "") << m(i, j);
    os << "]";
  }
  os << "]";
  return os.str();
}

std::string text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

[[noreturn]] void fail(const std::string& source, const std::string& key, const std::string& rule,
                       const std::string& value) {
  throw ConfigError(source, key, value, rule);
}

/// A YAML node plus where it came from, with typed, checked accessors.
class Reader {
 public:
  Reader(const YAML::Node& node, std::string source, std::string path)
      : node_(node), source_(std::move(source)), path_(std::move(path)) {}

  const YAML::Node& node() const { return node_; }
  const std::string& source() const { return source_; }
  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  const std::string& path() const { return path_; }

  [[noreturn]] void fail_key(const std::string& k, const std::string& rule, const std::string& value) const {
    fail(source_, key(k), rule, value);
  }

  void expect_map() const {
    if (!node_.IsMap()) fail(source_, path_.empty() ? "<top level>" : path_, "must be a map", flow(node_));
  }
  /// Unknown keys are errors (typos must not be silently ignored).
  void only_keys(std::initializer_list<const char*> allowed) const {
    expect_map();
    const std::set<std::string> ok(allowed.begin(), allowed.end());
    for (const auto& kv : node_) {
      const std::string k = kv.first.as<std::string>();
      if (!ok.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        throw ConfigError(source_ + ": " + key(k) + " is not a known key (allowed: " + list + ")");
      }
    }
  }
  bool has(const char* k) const { return node_[k].IsDefined() && !node_[k].IsNull(); }
  Reader child(const char* k) const {
    if (!has(k)) fail(source_, key(k), "is required", "nothing");
    return Reader(node_[k], source_, key(k));
  }
  Reader item(std::size_t i) const { return Reader(node_[i], source_, path_ + "[" + std::to_string(i) + "]"); }

  static double as_number(const YAML::Node& n, const std::string& source, const std::string& key) {
    double v = 0.0;
    if (!n.IsScalar()) fail(source, key, "must be a number", flow(n));
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(source, key, "must be a number", flow(n));
    }
    if (!std::isfinite(v)) fail(source, key, "must be finite (NaN/Inf not allowed)", flow(n));
    return v;
  }
  double number(const char* k) const {
    if (!has(k)) fail(source_, key(k), "is required", "nothing");
    return as_number(node_[k], source_, key(k));
  }
  double number(const char* k, double def) const { return has(k) ? number(k) : def; }
  std::string string(const char* k, const std::string& def) const {
    if (!has(k)) return def;
    if (!node_[k].IsScalar()) fail(source_, key(k), "must be a string", flow(node_[k]));
    return node_[k].as<std::string>();
  }
  /// A list of n numbers.
  Eigen::VectorXd vector(const char* k, int n) const {
    if (!has(k)) fail(source_, key(k), "is required", "nothing");
    const YAML::Node& s = node_[k];
    if (!s.IsSequence() || static_cast<int>(s.size()) != n)
      fail(source_, key(k), "must be a list of " + std::to_string(n) + " numbers", flow(s));
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i)
      v(i) = as_number(s[static_cast<std::size_t>(i)], source_, key(k) + "[" + std::to_string(i) + "]");
    return v;
  }
  Eigen::Vector3d vec3(const char* k) const { return vector(k, 3); }
  Eigen::Vector3d vec3(const char* k, const Eigen::Vector3d& def) const { return has(k) ? vec3(k) : def; }

 private:
  YAML::Node node_;
  std::string source_;
  std::string path_;
};

YAML::Node load_file(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(path + ": malformed YAML: " + e.what());
  }
}

// A vehicle file's thruster_defaults: the propeller keys of a thruster.
struct ThrusterCoefficients {
  ThrusterParams* t;
  template <class Archive>
  void Serialize(Archive* a) {
    t->SerializeCoefficients(a);
  }
};

// The keys a vehicle file must give (the rest have defaults).
void require_keys(const YAML::Node& node, const std::string& source, const std::string& path,
                  std::initializer_list<const char*> keys) {
  for (const char* k : keys) {
    const YAML::Node v = node[k];
    if (!v.IsDefined() || v.IsNull()) throw ConfigError(source, path.empty() ? k : path + "." + k, "", "is required");
  }
}

}  // namespace

// --- VehicleParams ------------------------------------------------------------------------------

double ThrusterParams::max_forward_thrust() const { return C_T * rho * w_max * w_max * std::pow(diameter, 4); }
double ThrusterParams::max_reverse_thrust() const {
  return (C_T_reverse > 0.0 ? C_T_reverse : C_T) * rho * w_max * w_max * std::pow(diameter, 4);
}

double VehicleParams::buoyancy_force(const EnvironmentParams& env) const {
  if (buoyancy >= 0.0) return buoyancy;
  if (volume > 0.0) return env.water_density * env.gravity * volume;
  return mass * env.gravity;
}

Matrix6d VehicleParams::rigid_body_mass() const {
  const Eigen::Matrix3d S = skew(r_g_B);
  Matrix6d M = Matrix6d::Zero();
  M.topLeftCorner<3, 3>() = mass * Eigen::Matrix3d::Identity();
  M.topRightCorner<3, 3>() = -mass * S;
  M.bottomLeftCorner<3, 3>() = mass * S;
  M.bottomRightCorner<3, 3>() = inertia - mass * S * S;  // parallel axis: I_o = I_g - m S(r_g)^2
  return M;
}

void validate_vehicle(const VehicleParams& p, const std::string& src) {
  if (!(std::isfinite(p.mass) && p.mass > 0.0)) fail(src, "mass", "must be > 0 kg", text(p.mass));
  if (!p.inertia.allFinite()) fail(src, "inertia", "must be finite", text(p.inertia));
  if (!p.inertia.isApprox(p.inertia.transpose(), 1e-9) &&
      (p.inertia - p.inertia.transpose()).cwiseAbs().maxCoeff() > 1e-12)
    fail(src, "inertia", "must be symmetric", text(p.inertia));
  {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(p.inertia);
    const Eigen::Vector3d& e = es.eigenvalues();  // ascending
    if (!(e(0) > 0.0)) fail(src, "inertia", "must be positive definite (eigenvalues " + text(e) + ")", text(p.inertia));
    if (e(0) + e(1) < e(2) * (1.0 - 1e-9))
      fail(src, "inertia", "principal moments must satisfy the triangle inequality (eigenvalues " + text(e) + ")",
           text(p.inertia));
  }
  if (!p.r_g_B.allFinite()) fail(src, "center_of_gravity", "must be finite", text(p.r_g_B));
  if (!p.r_b_B.allFinite()) fail(src, "center_of_buoyancy", "must be finite", text(p.r_b_B));
  if (!std::isfinite(p.buoyancy)) fail(src, "buoyancy", "must be finite", text(p.buoyancy));
  if (!(std::isfinite(p.volume) && p.volume >= 0.0)) fail(src, "volume", "must be >= 0 m^3", text(p.volume));
  if (!(std::isfinite(p.height) && p.height > 0.0)) fail(src, "height", "must be > 0 m", text(p.height));

  if (!p.added_mass.allFinite()) fail(src, "added_mass", "must be finite", text(p.added_mass));
  if ((p.added_mass - p.added_mass.transpose()).cwiseAbs().maxCoeff() >
      1e-9 * (1.0 + p.added_mass.cwiseAbs().maxCoeff()))
    fail(src, "added_mass", "must be symmetric", text(p.added_mass));
  if (p.rigid_body_mass().allFinite() && (p.rigid_body_mass() + p.added_mass).llt().info() != Eigen::Success)
    fail(src, "added_mass", "must make M_RB + M_A positive definite", text(p.added_mass));
  for (const auto& [name, D] : {std::pair<const char*, const Matrix6d*>{"linear_damping", &p.linear_damping},
                                {"quadratic_damping", &p.quadratic_damping}}) {
    if (!D->allFinite()) fail(src, name, "must be finite", text(*D));
    if ((D->diagonal().array() < 0.0).any())
      fail(src, name, "must have a non-negative diagonal (negative damping adds energy)", text(*D));
  }
  const auto& c = p.contact;
  if (!(std::isfinite(c.stiffness) && c.stiffness > 0.0))
    fail(src, "contact.stiffness", "must be > 0 N/m", text(c.stiffness));
  if (!(std::isfinite(c.damping) && c.damping >= 0.0))
    fail(src, "contact.damping", "must be >= 0 N s/m", text(c.damping));
  if (!(std::isfinite(c.friction) && c.friction >= 0.0))
    fail(src, "contact.friction", "must be >= 0 N s/m", text(c.friction));

  if (p.thrusters.size() > static_cast<std::size_t>(kMaxThrusters))
    fail(src, "thrusters", "must have at most " + std::to_string(kMaxThrusters) + " entries",
         std::to_string(p.thrusters.size()) + " thrusters");
  for (std::size_t i = 0; i < p.thrusters.size(); ++i) {
    const ThrusterParams& t = p.thrusters[i];
    const std::string k = "thrusters[" + std::to_string(i) + "]";
    if (!t.position_B.allFinite()) fail(src, k + ".position", "must be finite", text(t.position_B));
    if (!t.direction_B.allFinite()) fail(src, k + ".direction", "must be finite", text(t.direction_B));
    if (!(t.direction_B.norm() > 1e-9)) {
      throw ConfigError(src, k + ".direction", text(t.direction_B), "has zero length");
    }
    auto positive = [&](const char* key, double v, const char* unit) {
      if (!(std::isfinite(v) && v > 0.0)) fail(src, k + "." + key, std::string("must be > 0 ") + unit, text(v));
    };
    positive("C_T", t.C_T, "");
    positive("rho", t.rho, "kg/m^3");
    positive("w_max", t.w_max, "rev/s");
    positive("diameter", t.diameter, "m");
    positive("time_constant", t.time_constant, "s");
    if (!(std::isfinite(t.C_T_reverse) && t.C_T_reverse >= 0.0))
      fail(src, k + ".C_T_reverse", "must be >= 0 (0: same as C_T)", text(t.C_T_reverse));
  }
  validate_sensors(p.sensors, src);
}

VehicleParams parse_vehicle(const YAML::Node& node, const std::string& source) {
  // The schema is VehicleParams::Serialize (unav_common/config.hpp reads, checks and names every
  // key); what depends on which keys are given is settled on the YAML first: required keys,
  // buoyancy 'neutral' (the default) or a number exclusive with volume, thruster_defaults under
  // every thruster entry that does not set the key itself, default thruster names, and a sensor
  // (and the tether) whose section is given is enabled unless it says otherwise.
  if (!node.IsMap()) throw ConfigError(source, "", flow(node), "must be a mapping (a vehicle)");
  require_keys(node, source, "", {"mass", "inertia", "added_mass", "linear_damping", "quadratic_damping", "thrusters"});
  YAML::Node y = YAML::Clone(node);
  // buoyancy: 'neutral', a force >= 0, or (as VehicleParams writes an unset one) negative; a
  // neutral or given force excludes a volume > 0.
  const YAML::Node buoyancy = y["buoyancy"], volume = y["volume"];
  const bool neutral = buoyancy.IsScalar() && buoyancy.Scalar() == "neutral";
  double b = -1.0, v = 0.0;
  const bool b_set = neutral || (buoyancy.IsScalar() && YAML::convert<double>::decode(buoyancy, b) && b >= 0.0);
  const bool v_set = volume.IsScalar() && YAML::convert<double>::decode(volume, v) && v > 0.0;
  if (b_set && v_set)
    throw ConfigError(source, "buoyancy", flow(buoyancy), "and volume are exclusive: set one of them");
  if (neutral) y.remove("buoyancy");
  ThrusterParams defaults;
  ThrusterCoefficients coefficients{&defaults};
  YAML::Node given_defaults(YAML::NodeType::Map);
  if (y["thruster_defaults"].IsDefined()) {
    unav::common::LoadYaml(y, source, &coefficients, "thruster_defaults");
    if (y["thruster_defaults"].IsMap()) given_defaults = y["thruster_defaults"];
    y.remove("thruster_defaults");
  }
  YAML::Node thrusters = y["thrusters"];
  if (!thrusters.IsSequence() || thrusters.size() == 0)
    throw ConfigError(source, "thrusters", flow(thrusters), "must be a non-empty list");
  for (std::size_t i = 0; i < thrusters.size(); ++i) {
    YAML::Node t = thrusters[i];
    const std::string path = "thrusters[" + std::to_string(i) + "]";
    if (!t.IsMap()) throw ConfigError(source, path, flow(t), "must be a mapping (a thruster)");
    require_keys(t, source, path, {"position", "direction"});
    if (!t["name"].IsDefined()) t["name"] = "T" + std::to_string(i + 1);
    for (const auto& kv : given_defaults)
      if (!t[kv.first.Scalar()].IsDefined()) t[kv.first.Scalar()] = YAML::Clone(kv.second);
  }
  if (y["tether"].IsMap() && !y["tether"]["enabled"].IsDefined()) y["tether"]["enabled"] = true;
  YAML::Node sensors = y["sensors"];
  if (sensors.IsMap()) {
    for (auto kv : sensors) {
      YAML::Node section = kv.second;
      if (section.IsMap() && !section["enabled"].IsDefined()) section["enabled"] = true;
    }
  }
  VehicleParams p;
  unav::common::LoadYaml(y, source, &p);
  for (std::size_t i = 0; i < p.thrusters.size(); ++i) {
    ThrusterParams& t = p.thrusters[i];
    if (!(t.direction_B.norm() > 1e-9))
      throw ConfigError(source, "thrusters[" + std::to_string(i) + "].direction", text(t.direction_B),
                        "has zero length");
    t.direction_B.normalize();
  }
  validate_vehicle(p, source);
  return p;
}

VehicleParams load_vehicle(const std::string& yaml_path) { return parse_vehicle(load_file(yaml_path), yaml_path); }

VehicleParams bluerov2_heavy_params() {
  VehicleParams p;
  p.name = "bluerov2_heavy";
  p.mass = 13.5;
  p.inertia = Eigen::Vector3d(0.26, 0.23, 0.37).asDiagonal();
  p.r_g_B.setZero();
  p.r_b_B = Eigen::Vector3d(0.0, 0.0, -0.01);
  p.buoyancy = -1.0;  // neutral
  p.height = 0.254;
  p.added_mass.diagonal() << 6.3567, 7.1206, 18.6863, 0.1858, 0.1348, 0.2215;
  p.linear_damping.diagonal() << 13.7, 0.0, 33.0, 0.0, 0.8, 0.0;
  p.quadratic_damping.diagonal() << 141.0, 217.0, 190.0, 1.192, 0.470, 1.500;
  const double pos[8][3] = {{0.156, 0.111, 0.085},   {0.156, -0.111, 0.085}, {-0.156, 0.111, 0.085},
                            {-0.156, -0.111, 0.085}, {0.120, 0.218, 0.0},    {0.120, -0.218, 0.0},
                            {-0.120, 0.218, 0.0},    {-0.120, -0.218, 0.0}};
  const double dir[8][3] = {{0.7071, -0.7071, 0}, {0.7071, 0.7071, 0}, {-0.7071, -0.7071, 0},
                            {-0.7071, 0.7071, 0}, {0, 0, -1},          {0, 0, -1},
                            {0, 0, -1},           {0, 0, -1}};
  for (int i = 0; i < 8; ++i) {
    ThrusterParams t;
    t.name = "T" + std::to_string(i + 1);
    t.position_B = Eigen::Vector3d(pos[i][0], pos[i][1], pos[i][2]);
    t.direction_B = Eigen::Vector3d(dir[i][0], dir[i][1], dir[i][2]).normalized();
    p.thrusters.push_back(t);
  }
  return p;
}

// --- currents -----------------------------------------------------------------------------------

std::unique_ptr<CurrentModel> make_current(const YAML::Node& node, const std::string& source, const std::string& key) {
  const Reader r(node, source, key);
  r.expect_map();
  const std::string type = r.string("type", "");
  if (type == "constant") {
    r.only_keys({"type", "velocity"});
    return std::make_unique<ConstantCurrent>(r.vec3("velocity"));
  }
  if (type == "sinusoidal") {
    r.only_keys({"type", "mean", "amplitude", "frequency", "phase"});
    const double f = r.number("frequency");
    if (!(f > 0.0)) r.fail_key("frequency", "must be > 0 Hz", text(f));
    return std::make_unique<SinusoidalCurrent>(r.vec3("mean", Eigen::Vector3d::Zero()), r.vec3("amplitude"), f,
                                               r.number("phase", 0.0));
  }
  if (type == "sum_of_sines") {
    r.only_keys({"type", "mean", "components"});
    const Reader cs = r.child("components");
    if (!cs.node().IsSequence() || cs.node().size() == 0)
      fail(source, cs.path(), "must be a non-empty list", flow(cs.node()));
    std::vector<SumOfSinesCurrent::Component> comps;
    for (std::size_t i = 0; i < cs.node().size(); ++i) {
      const Reader c = cs.item(i);
      c.only_keys({"amplitude", "frequency", "phase"});
      SumOfSinesCurrent::Component comp;
      comp.amplitude_W = c.vec3("amplitude");
      comp.frequency_hz = c.number("frequency");
      if (!(comp.frequency_hz > 0.0)) c.fail_key("frequency", "must be > 0 Hz", text(comp.frequency_hz));
      comp.phase_rad = c.number("phase", 0.0);
      comps.push_back(comp);
    }
    return std::make_unique<SumOfSinesCurrent>(r.vec3("mean", Eigen::Vector3d::Zero()), std::move(comps));
  }
  if (type == "gauss_markov") {
    r.only_keys({"type", "mean", "stddev", "time_constant", "seed", "initial"});
    const Eigen::Vector3d mean = r.vec3("mean", Eigen::Vector3d::Zero());
    const Eigen::Vector3d sd = r.vec3("stddev");
    if ((sd.array() < 0.0).any()) r.fail_key("stddev", "must be >= 0 m/s on every axis", text(sd));
    const double tc = r.number("time_constant");
    if (!(tc > 0.0)) r.fail_key("time_constant", "must be > 0 s", text(tc));
    const double seed = r.number("seed", 0.0);
    if (seed < 0 || seed != std::floor(seed)) r.fail_key("seed", "must be a non-negative integer", text(seed));
    return std::make_unique<GaussMarkovCurrent>(mean, sd, tc, static_cast<std::uint64_t>(seed),
                                                r.vec3("initial", mean));
  }
  r.fail_key("type", "must be one of constant, sinusoidal, sum_of_sines, gauss_markov", flow(node["type"]));
}

std::unique_ptr<CurrentModel> load_current(const std::string& yaml_path) {
  const YAML::Node root = load_file(yaml_path);
  if (root.IsMap() && root["current"].IsDefined()) {
    Reader(root, yaml_path, "").only_keys({"current"});
    return make_current(root["current"], yaml_path, "current");
  }
  return make_current(root, yaml_path, "");
}

// --- seabed -------------------------------------------------------------------------------------

namespace {

// Reads a binary (P5) or ASCII (P2) PGM into rows of pixel values (top row first).
std::vector<std::vector<double>> read_pgm(const std::string& path, const std::string& source, const std::string& key,
                                          double* maxval) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(source, key, "names a file that cannot be opened", path);
  auto token = [&]() {
    std::string t;
    while (in >> t) {
      if (t[0] == '#') {
        std::string rest;
        std::getline(in, rest);
        continue;
      }
      return t;
    }
    fail(source, key, "names a truncated PGM file", path);
  };
  const std::string magic = token();
  if (magic != "P2" && magic != "P5") fail(source, key, "must name a PGM file (P2 or P5)", path);
  int w = 0, h = 0;
  try {
    w = std::stoi(token());
    h = std::stoi(token());
    *maxval = std::stod(token());
  } catch (const std::exception&) {
    fail(source, key, "names a PGM file with a bad header", path);
  }
  if (w < 1 || h < 1 || *maxval < 1 || *maxval > 65535) fail(source, key, "names a PGM file with a bad header", path);
  std::vector<std::vector<double>> px(static_cast<std::size_t>(h), std::vector<double>(static_cast<std::size_t>(w)));
  if (magic == "P5") {
    in.get();  // single whitespace after maxval
    const int bytes = *maxval > 255 ? 2 : 1;
    for (auto& row : px)
      for (auto& v : row) {
        unsigned char b[2] = {0, 0};
        in.read(reinterpret_cast<char*>(b), bytes);
        v = bytes == 2 ? b[0] * 256.0 + b[1] : b[0];
      }
    if (!in) fail(source, key, "names a truncated PGM file", path);
  } else {
    for (auto& row : px)
      for (auto& v : row) v = std::stod(token());
  }
  return px;
}

}  // namespace

std::unique_ptr<Seabed> make_seabed(const YAML::Node& node, const std::string& source, const std::string& key) {
  const Reader r(node, source, key);
  r.expect_map();
  const std::string type = r.string("type", "");
  if (type == "flat") {
    r.only_keys({"type", "depth"});
    return std::make_unique<FlatSeabed>(r.number("depth"));
  }
  auto resolution = [&] {
    const double res = r.number("resolution");
    if (!(res > 0.0)) r.fail_key("resolution", "must be > 0 m", text(res));
    return res;
  };
  if (type == "grid") {
    r.only_keys({"type", "origin_N", "origin_E", "resolution", "depths"});
    const Reader d = r.child("depths");
    const YAML::Node& rows = d.node();
    if (!rows.IsSequence() || rows.size() == 0) fail(source, d.path(), "must be a non-empty list of rows", flow(rows));
    std::vector<std::vector<double>> depths;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string rk = d.path() + "[" + std::to_string(i) + "]";
      if (!rows[i].IsSequence() || rows[i].size() != rows[0].size() || rows[i].size() == 0)
        fail(source, rk, "must be a list with as many values as the first row", flow(rows[i]));
      std::vector<double> row;
      for (std::size_t j = 0; j < rows[i].size(); ++j)
        row.push_back(Reader::as_number(rows[i][j], source, rk + "[" + std::to_string(j) + "]"));
      depths.push_back(std::move(row));
    }
    return std::make_unique<GridSeabed>(r.number("origin_N", 0.0), r.number("origin_E", 0.0), resolution(),
                                        std::move(depths));
  }
  if (type == "pgm") {
    r.only_keys({"type", "file", "origin_N", "origin_E", "resolution", "depth_white", "depth_black"});
    std::string file = r.string("file", "");
    if (file.empty()) r.fail_key("file", "is required", "nothing");
    if (file[0] != '/') {
      const auto slash = source.find_last_of('/');
      if (slash != std::string::npos) file = source.substr(0, slash + 1) + file;
    }
    double maxval = 255.0;
    auto px = read_pgm(file, source, r.key("file"), &maxval);
    const double white = r.number("depth_white"), black = r.number("depth_black");
    // Top image row = north-most row of the grid.
    std::vector<std::vector<double>> depths(px.rbegin(), px.rend());
    for (auto& row : depths)
      for (auto& v : row) v = black + (v / maxval) * (white - black);
    return std::make_unique<GridSeabed>(r.number("origin_N", 0.0), r.number("origin_E", 0.0), resolution(),
                                        std::move(depths));
  }
  r.fail_key("type", "must be one of flat, grid, pgm", flow(node["type"]));
}

std::unique_ptr<Seabed> load_seabed(const std::string& yaml_path) {
  const YAML::Node root = load_file(yaml_path);
  if (root.IsMap() && root["seabed"].IsDefined()) {
    Reader(root, yaml_path, "").only_keys({"seabed"});
    return make_seabed(root["seabed"], yaml_path, "seabed");
  }
  return make_seabed(root, yaml_path, "");
}

// --- environment --------------------------------------------------------------------------------

EnvironmentParams parse_environment(const YAML::Node& node, const std::string& source, const std::string& key) {
  const Reader r(node, source, key);
  r.only_keys({"gravity", "water_density", "atmospheric_pressure", "magnetic_field", "origin_latitude",
               "origin_longitude", "origin_altitude"});
  EnvironmentParams e;
  e.gravity = r.number("gravity", e.gravity);
  e.water_density = r.number("water_density", e.water_density);
  e.atmospheric_pressure = r.number("atmospheric_pressure", e.atmospheric_pressure);
  e.magnetic_field_W = r.vec3("magnetic_field", e.magnetic_field_W);
  e.origin_latitude_deg = r.number("origin_latitude", e.origin_latitude_deg);
  e.origin_longitude_deg = r.number("origin_longitude", e.origin_longitude_deg);
  e.origin_altitude_m = r.number("origin_altitude", e.origin_altitude_m);
  std::string msg;
  if (!e.IsValid(&msg)) throw ConfigError(source + ": " + (key.empty() ? "" : key + ".") + msg);
  return e;
}

}  // namespace unav::physics

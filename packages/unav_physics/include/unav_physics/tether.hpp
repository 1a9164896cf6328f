// The ROV's tether: a cable from a fixed point of the world (the support vessel, a tether
// management system) to an attachment point on the vehicle, as lumped masses joined by axial
// springs (a cable pulls, never pushes), each node with its wet weight (mass minus displaced
// water), added mass (the water it displaces), hydrodynamic drag on the flow relative to the water
// current (normal and tangential coefficients of a cylinder, Morison) and seabed contact (penalty
// normal force, regularized Coulomb friction). Integrated with the vehicle at the physics rate
// (semi-implicit Euler, sub-stepped below the axial springs' period); the force of the last
// segment acts on the vehicle at the attachment point. The length paid out can change during a run.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "unav_common/config.hpp"
#include "unav_physics/types.hpp"

namespace unav::physics {

class Seabed;

struct TetherParams {
  bool enabled = false;
  Eigen::Vector3d anchor_position{0.0, 0.0, 0.5};  ///< world NED: the surface end [m]
  Eigen::Vector3d attach_xyz_m{-0.22, 0.0, 0.0};   ///< on the vehicle, body FRD [m] (its stern)
  double length_m = 30.0;                          ///< paid out at the start
  int segments = 20;
  double diameter_m = 0.0076;
  double mass_per_m = 0.048;                  ///< in air, kg/m (the water it displaces: 0.047 kg/m at 7.6 mm)
  double axial_stiffness_n = 20000.0;         ///< E A [N]
  double damping_ratio = 0.5;                 ///< of each segment's axial spring
  double normal_drag_coefficient = 1.2;       ///< cross-flow drag of a cylinder
  double tangential_drag_coefficient = 0.01;  ///< skin friction along it (x pi d)
  double seabed_friction = 0.5;               ///< Coulomb coefficient on the seabed

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("enabled", &enabled).Doc("simulate the tether"));
    a->Visit(Field("anchor_position", &anchor_position).Range(-1e5, 1e5).Unit("m").Doc("world NED, the surface end"));
    a->Visit(Field("attach_xyz_m", &attach_xyz_m).Range(-10.0, 10.0).Unit("m").Doc("on the vehicle, FRD"));
    a->Visit(Field("length_m", &length_m).Above(0.0).Max(10000.0).Unit("m").Doc("paid out at the start"));
    a->Visit(Field("segments", &segments).Range(1, 1000).Doc("lumped masses between the ends"));
    a->Visit(Field("diameter_m", &diameter_m).Above(0.0).Max(0.5).Unit("m"));
    a->Visit(Field("mass_per_m", &mass_per_m).Above(0.0).Max(100.0).Unit("kg/m").Doc("in air"));
    a->Visit(Field("axial_stiffness_n", &axial_stiffness_n).Above(0.0).Max(1e9).Unit("N").Doc("E A"));
    a->Visit(Field("damping_ratio", &damping_ratio).Range(0.0, 10.0).Doc("of each segment's axial spring"));
    a->Visit(Field("normal_drag_coefficient", &normal_drag_coefficient).Range(0.0, 10.0));
    a->Visit(Field("tangential_drag_coefficient", &tangential_drag_coefficient).Range(0.0, 1.0));
    a->Visit(Field("seabed_friction", &seabed_friction).Range(0.0, 5.0).Doc("Coulomb coefficient"));
  }
};

class Tether {
 public:
  Tether(const TetherParams& params, const EnvironmentParams& env);
  /// The cable from the anchor to `attach_W`, at rest: straight, or, when longer than the
  /// distance, hanging in a V below it (its nodes at their rest spacing). Throws ConfigError when
  /// the cable is shorter than the distance.
  void reset(const Eigen::Vector3d& attach_W);
  /// The length paid out from now on [m] (> 0): the segments' rest length follows.
  void set_length(double length_m);
  /// Advances by dt with the vehicle's end at attach_W moving at attach_v_W, in a uniform water
  /// current current_W; seabed may be null.
  void step(double dt, const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W,
            const Eigen::Vector3d& current_W, const Seabed* seabed);
  /// The force of the cable on the vehicle at the attachment point (world NED) [N]: the last
  /// segment's pull and the wet weight and drag of the half segment at the vehicle's end.
  Eigen::Vector3d force_on_vehicle_W(const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W) const;
  /// The force of the cable on the anchor (world NED) [N].
  Eigen::Vector3d force_on_anchor_W() const;
  /// Node positions, the anchor first and the vehicle's end last (segments + 1).
  const std::vector<Eigen::Vector3d>& nodes() const { return p_; }
  const TetherParams& params() const { return prm_; }
  double length() const { return rest_ * prm_.segments; }

 private:
  Eigen::Vector3d segment_force(const Eigen::Vector3d& a, const Eigen::Vector3d& va, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& vb) const;  // on a, from the segment a-b
  Eigen::Vector3d node_drag(std::size_t i, const Eigen::Vector3d& v, double length) const;
  TetherParams prm_;
  EnvironmentParams env_;
  double rest_ = 1.0;             ///< rest length of a segment
  double k_ = 0.0;                ///< axial stiffness of a segment E A / rest
  double m_ = 0.0, m_eff_ = 0.0;  ///< node mass, with added mass
  double wet_weight_ = 0.0;       ///< of a node, N (+ down)
  double area_ = 0.0;             ///< cross-section
  std::vector<Eigen::Vector3d> p_, v_, f_;
  Eigen::Vector3d current_W_ = Eigen::Vector3d::Zero();  ///< the water's velocity at the last step
};

}  // namespace unav::physics

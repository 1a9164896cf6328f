// Sim(3) and Umeyama: the one implementation must give bit-identical results to the two it
// replaces, unav::localization::EstimateSim3 (SLAM) and unav::evaluation::umeyama (evo metrics).
// Verbatim copies of both (and of the localization Sim3 operations) are kept here as the
// reference; every coefficient is compared with EXPECT_EQ.
#include "unav_common/sim3.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/SVD>

namespace uc = unav::common;

namespace old_localization {  // packages/unav_localization sim3.hpp + slam_map.cpp, verbatim

struct Sim3 {
  double s = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Sim3() = default;
  Sim3(double scale, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
      : s(scale), R(rotation), t(translation) {}
  explicit Sim3(const Eigen::Isometry3d& T) : s(1.0), R(T.linear()), t(T.translation()) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return s * (R * x) + t; }
  Sim3 operator*(const Sim3& o) const { return {s * o.s, R * o.R, s * (R * o.t) + t}; }
  Sim3 inverse() const {
    const Eigen::Matrix3d Rt = R.transpose();
    return {1.0 / s, Rt, -(Rt * t) / s};
  }
  Eigen::Isometry3d ToIsometryUnscaled() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t / s;
    return T;
  }
};

bool EstimateSim3(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool fix_scale, Sim3* S) {
  if (from.cols() < 3 || from.cols() != to.cols()) return false;
  const Eigen::Vector3d mf = from.rowwise().mean(), mt = to.rowwise().mean();
  const Eigen::Matrix3Xd a = from.colwise() - mf, b = to.colwise() - mt;
  const double var_from = a.squaredNorm() / static_cast<double>(from.cols());
  if (!(var_from > 1e-12)) return false;
  const Eigen::Matrix3d cov = b * a.transpose() / static_cast<double>(from.cols());
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d& sv = svd.singularValues();
  if (!(sv(1) > 1e-9 * std::max(1.0, sv(0)))) return false;  // collinear
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) D(2, 2) = -1;
  S->R = svd.matrixU() * D * svd.matrixV().transpose();
  S->s = fix_scale ? 1.0 : (sv.asDiagonal() * D).trace() / var_from;
  S->t = mt - S->s * S->R * mf;
  return std::isfinite(S->s) && S->s > 0;
}

}  // namespace old_localization

namespace old_evaluation {  // packages/unav_evaluation metrics.hpp + metrics.cpp, verbatim

struct TrajectoryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Sim3 {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double s = 1.0;
};

Sim3 umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  if (src.cols() != dst.cols() || src.cols() < 2)
    throw TrajectoryError("umeyama: need the same number (>= 2) of source and destination points, got " +
                          std::to_string(src.cols()) + " and " + std::to_string(dst.cols()));
  const double n = static_cast<double>(src.cols());
  const Eigen::Vector3d mean_src = src.rowwise().mean();
  const Eigen::Vector3d mean_dst = dst.rowwise().mean();
  const Eigen::Matrix3Xd src_c = src.colwise() - mean_src;
  const Eigen::Matrix3Xd dst_c = dst.colwise() - mean_dst;
  const double sigma_src = src_c.squaredNorm() / n;
  const Eigen::Matrix3d cov = dst_c * src_c.transpose() / n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  Sim3 out;
  out.R = svd.matrixU() * S * svd.matrixV().transpose();
  if (with_scale) {
    if (sigma_src <= 0.0) throw TrajectoryError("umeyama: source points have no spread (all identical)");
    out.s = (svd.singularValues().asDiagonal() * S).trace() / sigma_src;
  }
  out.t = mean_dst - out.s * out.R * mean_src;
  return out;
}

}  // namespace old_evaluation

namespace {

// How each caller reproduces its old contract on top of unav::common::Umeyama (the wrappers
// the lead installs in the two packages).
bool EstimateSim3Via(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool fix_scale, uc::Sim3* S) {
  uc::UmeyamaOptions o;  // defaults = the SLAM's rules: >= 3 points, variance > 1e-12, collinear 1e-9
  o.with_scale = !fix_scale;
  const uc::UmeyamaResult r = uc::Umeyama(from, to, o);
  if (r.status == uc::UmeyamaStatus::kSizeMismatch || r.status == uc::UmeyamaStatus::kTooFewPoints ||
      r.status == uc::UmeyamaStatus::kNoSpread || r.status == uc::UmeyamaStatus::kCollinear)
    return false;  // the old code returned before writing *S
  *S = r.S;        // kBadScale: written, then false (as before)
  return r.ok();
}

uc::Sim3 EvoUmeyamaVia(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  uc::UmeyamaOptions o;
  o.with_scale = with_scale;
  o.min_points = 2;
  const uc::UmeyamaResult r = uc::Umeyama(src, dst, o);
  if (r.status == uc::UmeyamaStatus::kSizeMismatch || r.status == uc::UmeyamaStatus::kTooFewPoints)
    throw old_evaluation::TrajectoryError("umeyama: need the same number (>= 2) of source and destination points");
  if (with_scale && r.source_variance <= 0.0)
    throw old_evaluation::TrajectoryError("umeyama: source points have no spread (all identical)");
  return r.S;  // evo accepts collinear points and any scale
}

void ExpectBitEqual(const uc::Sim3& a, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double s,
                    const std::string& what) {
  EXPECT_EQ(a.s, s) << what;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.t(i), t(i)) << what << " t(" << i << ")";
    for (int j = 0; j < 3; ++j) EXPECT_EQ(a.R(i, j), R(i, j)) << what << " R(" << i << "," << j << ")";
  }
}

Eigen::Matrix3d RandomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
}

/// Point pairs to ~ s R from + t + noise, in several flavours (SLAM-like map points, trajectory
/// positions far from the origin, mirrored sets that trigger the reflection fix, tiny sets).
void RandomPairs(std::mt19937_64& rng, int trial, Eigen::Matrix3Xd* from, Eigen::Matrix3Xd* to) {
  std::uniform_int_distribution<int> count(3, 60);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const int n = trial % 7 == 0 ? 3 : count(rng);
  const double spread = std::pow(10.0, 3.0 * u(rng));
  const Eigen::Vector3d offset = Eigen::Vector3d(u(rng), u(rng), u(rng)) * (trial % 3 == 0 ? 1e4 : 10.0);
  from->resize(3, n);
  for (int i = 0; i < n; ++i) from->col(i) = offset + spread * Eigen::Vector3d(g(rng), g(rng), g(rng));
  const Eigen::Matrix3d R = RandomRotation(rng);
  const double s = std::exp(2.0 * u(rng));
  const Eigen::Vector3d t(5 * u(rng), 5 * u(rng), 5 * u(rng));
  const double noise = trial % 4 == 0 ? 0.0 : spread * 0.05 * std::abs(u(rng));
  to->resize(3, n);
  for (int i = 0; i < n; ++i) to->col(i) = s * (R * from->col(i)) + t + noise * Eigen::Vector3d(g(rng), g(rng), g(rng));
  if (trial % 5 == 1) to->row(2) *= -1.0;  // a mirror image: det(U) det(V) < 0
}

TEST(Umeyama, BitIdenticalToTheSlamEstimateSim3) {
  std::mt19937_64 rng(20240611);
  int written = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3Xd from, to;
    RandomPairs(rng, trial, &from, &to);
    for (bool fix_scale : {false, true}) {
      old_localization::Sim3 expected(7.0, Eigen::Matrix3d::Constant(3.0), Eigen::Vector3d::Constant(5.0));
      uc::Sim3 got(7.0, Eigen::Matrix3d::Constant(3.0), Eigen::Vector3d::Constant(5.0));
      const bool ok_old = old_localization::EstimateSim3(from, to, fix_scale, &expected);
      const bool ok_new = EstimateSim3Via(from, to, fix_scale, &got);
      ASSERT_EQ(ok_old, ok_new) << "trial " << trial;
      ExpectBitEqual(got, expected.R, expected.t, expected.s, "trial " + std::to_string(trial));
      written += ok_old;
      // The core's own status agrees with the old boolean.
      uc::UmeyamaOptions o;
      o.with_scale = !fix_scale;
      EXPECT_EQ(uc::Umeyama(from, to, o).ok(), ok_old);
    }
  }
  EXPECT_GT(written, 3900);
}

TEST(Umeyama, BitIdenticalToTheEvoUmeyama) {
  std::mt19937_64 rng(77);
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3Xd src, dst;
    RandomPairs(rng, trial, &src, &dst);
    if (trial % 11 == 0) {  // two points, as evo allows
      src.conservativeResize(3, 2);
      dst.conservativeResize(3, 2);
    }
    for (bool with_scale : {true, false}) {
      const old_evaluation::Sim3 expected = old_evaluation::umeyama(src, dst, with_scale);
      const uc::Sim3 got = EvoUmeyamaVia(src, dst, with_scale);
      ExpectBitEqual(got, expected.R, expected.t, expected.s, "trial " + std::to_string(trial));
      // evo's align applies R * (s * p) + t.
      const Eigen::Vector3d p = src.col(0);
      const Eigen::Vector3d aligned_old = expected.R * (expected.s * p) + expected.t;
      const Eigen::Vector3d aligned_new = got.TransformScaleFirst(p);
      for (int i = 0; i < 3; ++i) EXPECT_EQ(aligned_new(i), aligned_old(i));
    }
  }
}

TEST(Umeyama, DegenerateInputsFollowEachCallersOldRules) {
  const Eigen::Matrix3Xd line = (Eigen::Matrix3Xd(3, 4) << 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3).finished();
  const Eigen::Matrix3Xd same = Eigen::Matrix3Xd::Ones(3, 4);
  const Eigen::Matrix3Xd two = (Eigen::Matrix3Xd(3, 2) << 0, 1, 0, 2, 0, 3).finished();
  const Eigen::Matrix3Xd shifted_two = two.colwise() + Eigen::Vector3d(1, 2, 3);
  const Eigen::Matrix3Xd three = (Eigen::Matrix3Xd(3, 3) << 0, 1, 0, 0, 0, 1, 0, 0, 0).finished();
  uc::Sim3 S;
  old_localization::Sim3 S_old;
  for (const Eigen::Matrix3Xd* m : {&line, &same, &two}) {
    EXPECT_EQ(old_localization::EstimateSim3(*m, *m, false, &S_old), EstimateSim3Via(*m, *m, false, &S));
  }
  EXPECT_EQ(uc::Umeyama(line, line).status, uc::UmeyamaStatus::kCollinear);
  EXPECT_EQ(uc::Umeyama(same, same).status, uc::UmeyamaStatus::kNoSpread);
  EXPECT_EQ(uc::Umeyama(two, two).status, uc::UmeyamaStatus::kTooFewPoints);
  EXPECT_EQ(uc::Umeyama(two, three).status, uc::UmeyamaStatus::kSizeMismatch);
  // All destination points equal: scale 0, rejected by the default rules, kept by evo's.
  const Eigen::Matrix3Xd zero_to = Eigen::Matrix3Xd::Zero(3, 3);
  EXPECT_EQ(uc::Umeyama(three, zero_to).status, uc::UmeyamaStatus::kCollinear);
  EXPECT_FALSE(uc::Umeyama(three, zero_to).message().empty());

  // evo: two points and collinear sets are accepted (bit-identical), identical points throw
  // with scale and are accepted without.
  for (const auto& [a, b] : {std::pair{&two, &shifted_two}, std::pair{&line, &line}}) {
    for (bool with_scale : {true, false}) {
      const auto e = old_evaluation::umeyama(*a, *b, with_scale);
      ExpectBitEqual(EvoUmeyamaVia(*a, *b, with_scale), e.R, e.t, e.s, "degenerate");
    }
  }
  EXPECT_THROW(old_evaluation::umeyama(same, same, true), old_evaluation::TrajectoryError);
  EXPECT_THROW(EvoUmeyamaVia(same, same, true), old_evaluation::TrajectoryError);
  const auto e = old_evaluation::umeyama(same, same, false);
  ExpectBitEqual(EvoUmeyamaVia(same, same, false), e.R, e.t, e.s, "no spread, no scale");
  EXPECT_THROW(EvoUmeyamaVia(two, three, true), old_evaluation::TrajectoryError);
  const Eigen::Matrix3Xd one = Eigen::Matrix3Xd::Zero(3, 1);
  EXPECT_THROW(EvoUmeyamaVia(one, one, false), old_evaluation::TrajectoryError);
}

TEST(Umeyama, RecoversAKnownSimilarity) {
  std::mt19937_64 rng(3);
  Eigen::Matrix3Xd from(3, 10);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < 10; ++i) from.col(i) = Eigen::Vector3d(g(rng), g(rng), g(rng));
  const uc::Sim3 truth(2.5, RandomRotation(rng), Eigen::Vector3d(1, -2, 3));
  Eigen::Matrix3Xd to(3, 10);
  for (int i = 0; i < 10; ++i) to.col(i) = truth * Eigen::Vector3d(from.col(i));
  const uc::UmeyamaResult r = uc::Umeyama(from, to);
  ASSERT_TRUE(r.ok()) << r.message();
  // Exact data: only rounding error (~1e-15 relative) remains.
  EXPECT_NEAR(r.S.s, 2.5, 1e-12);
  EXPECT_LT((r.S.R - truth.R).norm(), 1e-12);
  EXPECT_LT((r.S.t - truth.t).norm(), 1e-12);
  uc::UmeyamaOptions rigid;
  rigid.with_scale = false;
  EXPECT_EQ(uc::Umeyama(from, to, rigid).S.s, 1.0);
}

TEST(Sim3, OperationsBitIdenticalToTheSlamSim3) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Matrix3d Ra = RandomRotation(rng), Rb = RandomRotation(rng);
    const Eigen::Vector3d ta(u(rng), u(rng), u(rng)), tb(u(rng), u(rng), u(rng)), x(u(rng), u(rng), u(rng));
    const double sa = std::exp(u(rng)), sb = std::exp(u(rng));
    const old_localization::Sim3 oa(sa, Ra, ta), ob(sb, Rb, tb);
    const uc::Sim3 a(sa, Ra, ta), b(sb, Rb, tb);
    const old_localization::Sim3 oab = oa * ob, oinv = oa.inverse();
    ExpectBitEqual(a * b, oab.R, oab.t, oab.s, "compose");
    ExpectBitEqual(a.inverse(), oinv.R, oinv.t, oinv.s, "inverse");
    const Eigen::Vector3d y_old = oa * x, y_new = a * x;
    for (int i = 0; i < 3; ++i) EXPECT_EQ(y_new(i), y_old(i));
    const Eigen::Isometry3d T_old = oa.ToIsometryUnscaled(), T_new = a.ToIsometryUnscaled();
    for (int i = 0; i < 16; ++i) EXPECT_EQ(T_new.matrix()(i), T_old.matrix()(i));
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Ra;
    X.translation() = ta;
    const old_localization::Sim3 oX(X);
    ExpectBitEqual(uc::Sim3(X), oX.R, oX.t, oX.s, "from isometry");
  }
  // Algebra: S * S^-1 = identity, (A B) x = A (B x) up to rounding.
  const uc::Sim3 A(2.0, RandomRotation(rng), Eigen::Vector3d(1, 2, 3));
  const uc::Sim3 I = A * A.inverse();
  EXPECT_NEAR(I.s, 1.0, 1e-15);
  EXPECT_LT((I.R - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_LT(I.t.norm(), 1e-14);
}

}  // namespace

// Sim(3) and Umeyama (Eigen::umeyama's rotation, our scale, translation and rejection rules):
// exact recovery of a known similarity, least-squares optimality on noisy sets (no perturbation
// of the estimate lowers the residual), the reflection fix, the degenerate inputs' statuses, and
// the Sim(3) algebra.
#include "unav_common/sim3.hpp"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

namespace uc = unav::common;

namespace {

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

double Residual(const uc::Sim3& S, const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  double r = 0.0;
  for (Eigen::Index i = 0; i < from.cols(); ++i) r += (to.col(i) - S * Eigen::Vector3d(from.col(i))).squaredNorm();
  return r;
}

TEST(Umeyama, RecoversExactSimilaritiesAndIsOptimalOnNoisySets) {
  std::mt19937_64 rng(20240611);
  std::normal_distribution<double> g(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3Xd from, to;
    RandomPairs(rng, trial, &from, &to);
    const uc::UmeyamaResult r = uc::Umeyama(from, to);
    if (!r.ok()) continue;  // nearly collinear draws (3 points)
    ++checked;
    const uc::Sim3& S = r.S;
    // A proper rotation (orthonormal to rounding, det +1).
    EXPECT_LT((S.R.transpose() * S.R - Eigen::Matrix3d::Identity()).norm(), 1e-12) << trial;
    EXPECT_NEAR(S.R.determinant(), 1.0, 1e-12) << trial;
    // Least squares over proper similarities (mirrored sets too, where the reflection fix
    // lowers the scale): small perturbations of s, R and t all raise the residual (relative 1e-9
    // slack for rounding in sums of up to 60 terms of magnitude up to 1e8).
    const double r0 = Residual(S, from, to);
    const double scale = std::sqrt(r.source_variance);
    for (int k = 0; k < 6; ++k) {
      const double eps = 1e-4;
      const Eigen::Vector3d w(g(rng), g(rng), g(rng));
      uc::Sim3 P = S;
      if (k < 2) P.s *= k == 0 ? 1.0 + eps : 1.0 - eps;
      if (k == 2 || k == 3) P.R = Eigen::AngleAxisd(eps, w.normalized()).toRotationMatrix() * S.R;
      if (k >= 4) P.t += eps * std::max(1.0, S.s * scale) * w.normalized();
      if (k == 2 || k == 3 || k >= 4) P.t += S.s * (S.R - P.R) * Eigen::Vector3d(from.rowwise().mean());
      EXPECT_GE(Residual(P, from, to), r0 * (1.0 - 1e-9)) << "trial " << trial << " perturbation " << k;
    }
  }
  EXPECT_GT(checked, 1500);
}

TEST(Umeyama, RejectsMirrorsWithAProperRotation) {
  // A mirror image has no proper similarity: the fit must still return det R = +1 (the
  // reflection fix), never the reflection that would fit exactly.
  std::mt19937_64 rng(77);
  for (int trial = 1; trial < 400; trial += 5) {
    Eigen::Matrix3Xd from, to;
    RandomPairs(rng, trial, &from, &to);
    const uc::UmeyamaResult r = uc::Umeyama(from, to);
    if (r.status == uc::UmeyamaStatus::kCollinear) continue;
    EXPECT_NEAR(r.S.R.determinant(), 1.0, 1e-12) << trial;
  }
}

TEST(Umeyama, DegenerateInputsHaveTheirStatus) {
  const Eigen::Matrix3Xd line = (Eigen::Matrix3Xd(3, 4) << 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3).finished();
  const Eigen::Matrix3Xd same = Eigen::Matrix3Xd::Ones(3, 4);
  const Eigen::Matrix3Xd two = (Eigen::Matrix3Xd(3, 2) << 0, 1, 0, 2, 0, 3).finished();
  const Eigen::Matrix3Xd three = (Eigen::Matrix3Xd(3, 3) << 0, 1, 0, 0, 0, 1, 0, 0, 0).finished();
  EXPECT_EQ(uc::Umeyama(line, line).status, uc::UmeyamaStatus::kCollinear);
  EXPECT_EQ(uc::Umeyama(same, same).status, uc::UmeyamaStatus::kNoSpread);
  EXPECT_EQ(uc::Umeyama(two, two).status, uc::UmeyamaStatus::kTooFewPoints);
  EXPECT_EQ(uc::Umeyama(two, three).status, uc::UmeyamaStatus::kSizeMismatch);
  // All destination points equal: scale 0 and singular values 0: rejected, named.
  const Eigen::Matrix3Xd zero_to = Eigen::Matrix3Xd::Zero(3, 3);
  const uc::UmeyamaResult z = uc::Umeyama(three, zero_to);
  EXPECT_EQ(z.status, uc::UmeyamaStatus::kCollinear);
  EXPECT_NE(z.message().find("collinear"), std::string::npos) << z.message();
  // The evaluator's rules (evo): two points and a line are accepted and still map exactly.
  uc::UmeyamaOptions evo;
  evo.min_points = 2;
  const Eigen::Matrix3Xd shifted_line = (2.0 * line).colwise() + Eigen::Vector3d(1, 2, 3);
  const uc::UmeyamaResult l = uc::Umeyama(line, shifted_line, evo);
  EXPECT_EQ(l.status, uc::UmeyamaStatus::kCollinear);
  EXPECT_NEAR(l.S.s, 2.0, 1e-12);
  for (int i = 0; i < 4; ++i) EXPECT_LT((l.S * Eigen::Vector3d(line.col(i)) - shifted_line.col(i)).norm(), 1e-12);
  // Without scale, identical points give the identity rotation and the centroids' offset.
  uc::UmeyamaOptions rigid;
  rigid.with_scale = false;
  const uc::UmeyamaResult n = uc::Umeyama(same, same, rigid);
  EXPECT_EQ(n.S.s, 1.0);
  EXPECT_LT(n.S.t.norm(), 1e-15);
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

TEST(Sim3, CompositionInverseAndIsometry) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 500; ++trial) {
    const uc::Sim3 A(std::exp(u(rng)), RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const uc::Sim3 B(std::exp(u(rng)), RandomRotation(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    // (A B) x = A (B x); A^-1 A x = x; scale-first order is the same map (to rounding, ~1e-13 at
    // scales up to e^3 and coordinates up to 3 m).
    EXPECT_LT(((A * B) * x - A * (B * x)).norm(), 1e-12) << trial;
    EXPECT_LT((A.inverse() * (A * x) - x).norm(), 1e-12) << trial;
    EXPECT_LT((A.TransformScaleFirst(x) - A * x).norm(), 1e-12) << trial;
    // The unscaled isometry: same rotation, translation / s.
    const Eigen::Isometry3d T = A.ToIsometryUnscaled();
    EXPECT_EQ(T.linear(), A.R);
    EXPECT_LT((T.translation() * A.s - A.t).norm(), 1e-12);
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = A.R;
    X.translation() = A.t;
    const uc::Sim3 rigid(X);
    EXPECT_EQ(rigid.s, 1.0);
    EXPECT_LT(((rigid * x) - (X * x)).norm(), 1e-12);
  }
  const uc::Sim3 A(2.0, RandomRotation(rng), Eigen::Vector3d(1, 2, 3));
  const uc::Sim3 I = A * A.inverse();
  EXPECT_NEAR(I.s, 1.0, 1e-15);
  EXPECT_LT((I.R - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_LT(I.t.norm(), 1e-14);
}

}  // namespace

// Materials against independent answers: the stress equals the finite-difference derivative of the
// energy, the tangent the finite-difference derivative of the stress (large strain, 1e-6 relative),
// objectivity under rigid rotations, and the linear elastic limit at F = I; the split tangent the
// assembly uses equals the full one.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "fem/material.h"

namespace fetouch::fem {
namespace {

constexpr double kE = 5000, kNu = 0.45;

std::vector<std::unique_ptr<Material>> all_materials(bool hyperelastic_only) {
  std::vector<std::unique_ptr<Material>> m;
  const double lambda = lame_lambda(kE, kNu), mu = lame_mu(kE, kNu), kappa = kE / (3 * (1 - 2 * kNu));
  if (!hyperelastic_only) m.push_back(std::make_unique<LinearElastic>(lambda, mu));
  m.push_back(std::make_unique<SaintVenantKirchhoff>(lambda, mu));
  m.push_back(std::make_unique<NeoHookean>(lambda, mu));
  m.push_back(std::make_unique<NearlyIncompressibleNeoHookean>(kappa, mu));
  m.push_back(std::make_unique<MooneyRivlin>(0.3 * mu, 0.2 * mu, kappa));
  return m;
}

Tensor2 rotation(double angle, dealii::Tensor<1, 3> axis) {
  axis /= axis.norm();
  Tensor2 r;
  const double c = std::cos(angle), s = std::sin(angle);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      r[i][j] = (i == j ? c : 0) + (1 - c) * axis[i] * axis[j];
      for (int k = 0; k < 3; ++k) {
        const int eps = (i == j || j == k || i == k) ? 0 : ((j - i + 3) % 3 == 1 ? 1 : -1);
        r[i][j] -= s * eps * axis[k];
      }
    }
  return r;
}

// Large strain: stretches in [0.55, 1.9], shears up to 0.5, a rotation.
Tensor2 random_deformation(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  Tensor2 stretch;
  for (int i = 0; i < 3; ++i) stretch[i][i] = 0.55 + 1.35 * u(rng);
  stretch[0][1] = 0.5 * (u(rng) - 0.5), stretch[1][2] = 0.5 * (u(rng) - 0.5), stretch[0][2] = 0.4 * (u(rng) - 0.5);
  dealii::Tensor<1, 3> axis;
  axis[0] = u(rng) - 0.5, axis[1] = u(rng) - 0.5, axis[2] = u(rng) + 0.1;
  return rotation(4 * u(rng), axis) * stretch;
}

TEST(Materials, StressIsTheEnergysDerivative) {
  std::mt19937 rng(7);
  for (const auto& material : all_materials(false))
    for (int t = 0; t < 20; ++t) {
      const Tensor2 F = random_deformation(rng);
      Tensor2 P;
      ASSERT_TRUE(material->evaluate(F, P, nullptr));
      const double h = 1e-6;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          Tensor2 plus = F, minus = F;
          plus[i][j] += h, minus[i][j] -= h;
          const double fd = (material->energy(plus) - material->energy(minus)) / (2 * h);
          // Central differences: O(h^2) truncation, round-off eps psi / h ~ 1e-10 of the scale.
          EXPECT_NEAR(P[i][j], fd, 1e-6 * P.norm()) << material->name() << " " << i << j;
        }
    }
}

TEST(Materials, TangentIsTheStresssDerivative) {
  std::mt19937 rng(8);
  for (const auto& material : all_materials(false))
    for (int t = 0; t < 20; ++t) {
      const Tensor2 F = random_deformation(rng);
      Tensor2 P;
      Tensor4 A;
      ASSERT_TRUE(material->evaluate(F, P, &A));
      const double h = 1e-6;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          Tensor2 plus = F, minus = F, p_plus, p_minus;
          plus[k][l] += h, minus[k][l] -= h;
          material->evaluate(plus, p_plus, nullptr);
          material->evaluate(minus, p_minus, nullptr);
          const Tensor2 fd = (p_plus - p_minus) / (2 * h);
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
              EXPECT_NEAR(A[i][j][k][l], fd[i][j], 1e-6 * A.norm()) << material->name() << " " << i << j << k << l;
        }
    }
}

TEST(Materials, RigidRotationsProduceNoStressAndRotateStress) {
  std::mt19937 rng(9);
  dealii::Tensor<1, 3> axis;
  axis[0] = 0.3, axis[1] = -0.5, axis[2] = 0.8;
  const Tensor2 q = rotation(1.2, axis);
  for (const auto& material : all_materials(true)) {
    Tensor2 P;
    ASSERT_TRUE(material->evaluate(q, P, nullptr));
    EXPECT_LT(P.norm(), 1e-9 * kE) << material->name();
    const Tensor2 F = random_deformation(rng);
    Tensor2 p_f, p_qf;
    material->evaluate(F, p_f, nullptr);
    material->evaluate(q * F, p_qf, nullptr);
    EXPECT_LT((p_qf - q * p_f).norm(), 1e-10 * p_f.norm()) << material->name();  // P(QF) = Q P(F)
  }
  // The small-strain reference is not objective: a finite rotation strains it.
  Tensor2 P;
  LinearElastic(lame_lambda(kE, kNu), lame_mu(kE, kNu)).evaluate(q, P, nullptr);
  EXPECT_GT(P.norm(), 0.1 * kE);
}

TEST(Materials, EveryModelReducesToLinearElasticityAtRest) {
  const double mu = lame_mu(kE, kNu), lambda = lame_lambda(kE, kNu);
  Tensor4 reference;
  Tensor2 P, identity;
  for (int i = 0; i < 3; ++i) identity[i][i] = 1;
  LinearElastic(lambda, mu).evaluate(identity, P, &reference);
  for (const auto& material : all_materials(true)) {
    Tensor4 A;
    ASSERT_TRUE(material->evaluate(identity, P, &A));
    EXPECT_LT(P.norm(), 1e-9 * kE) << material->name();  // stress-free reference configuration
    EXPECT_LT((A - reference).norm(), 1e-9 * reference.norm()) << material->name();
  }
}

// The five scalars and H of the split form rebuild evaluate()'s A and P (large strain), for the
// models that have one; the others say they have none and refuse.
TEST(Materials, SplitTangentRebuildsTheFullTangent) {
  std::mt19937 rng(10);
  int split_models = 0;
  for (const auto& material : all_materials(false)) {
    if (!material->has_split_tangent()) {
      Tensor2 P;
      SplitTangent s;
      EXPECT_THROW(material->evaluate_split(random_deformation(rng), P, s), std::logic_error) << material->name();
      continue;
    }
    ++split_models;
    for (int t = 0; t < 20; ++t) {
      const Tensor2 F = random_deformation(rng);
      Tensor2 P, p_split;
      Tensor4 A;
      SplitTangent s;
      ASSERT_TRUE(material->evaluate(F, P, &A));
      ASSERT_TRUE(material->evaluate_split(F, p_split, s));
      EXPECT_LT((p_split - P).norm(), 1e-12 * P.norm()) << material->name();
      Tensor4 rebuilt;
      for (int i = 0; i < 3; ++i)
        for (int J = 0; J < 3; ++J)
          for (int k = 0; k < 3; ++k)
            for (int L = 0; L < 3; ++L)
              rebuilt[i][J][k][L] = s.alpha * (i == k && J == L) + s.zeta * F[i][J] * F[k][L] +
                                    s.beta * s.H[i][J] * s.H[k][L] + s.gamma * s.H[i][L] * s.H[k][J] +
                                    s.eta * (F[i][J] * s.H[k][L] + s.H[i][J] * F[k][L]);
      EXPECT_LT((rebuilt - A).norm(), 1e-12 * A.norm()) << material->name();
    }
  }
  EXPECT_EQ(split_models, 3);  // linear elastic and both neo-Hookean models
  Tensor2 inverted, P;
  inverted[0][0] = -1, inverted[1][1] = 1, inverted[2][2] = 1;
  SplitTangent s;
  EXPECT_FALSE(NeoHookean(lame_lambda(kE, kNu), lame_mu(kE, kNu)).evaluate_split(inverted, P, s));
}

TEST(Materials, InvertedDeformationsAreRejected) {
  Tensor2 inverted;
  inverted[0][0] = -1, inverted[1][1] = 1, inverted[2][2] = 1;
  for (const auto& material : all_materials(true)) {
    Tensor2 P;
    EXPECT_FALSE(material->evaluate(inverted, P, nullptr)) << material->name();
    EXPECT_TRUE(std::isinf(material->energy(inverted))) << material->name();
  }
}

}  // namespace
}  // namespace fetouch::fem

// Tissue materials in total Lagrangian form: for a deformation gradient F, the strain energy
// density psi(F), the first Piola-Kirchhoff stress P = dpsi/dF and its consistent tangent
// A = dP/dF (A_iJkL = dP_iJ / dF_kL), which Newton's method needs for quadratic convergence.
//
// The hyperelastic models are isotropic: psi depends on F through I1 = tr C, I2 = (I1^2 - tr C^2)/2
// and J = det F (C = F'F). Each model gives psi and its first and second partial derivatives in
// (I1, I2, J); InvariantMaterial turns them into P and A with
//   dI1/dF = 2F,   dI2/dF = 2(I1 F - F C),   dJ/dF = J F^-T,
//   d2I1 = 2 d_ik d_JL,
//   d2I2 = 4 F_iJ F_kL + 2 I1 d_ik d_JL - 2 d_ik C_LJ - 2 F_iL F_kJ - 2 b_ik d_JL   (b = F F'),
//   d2J  = J (F^-T_iJ F^-T_kL - F^-T_iL F^-T_kJ).
// Models (mu, lambda Lame constants; kappa bulk modulus; U(J) = kappa/4 (J^2 - 1 - 2 ln J)):
//   linear elastic            sigma = lambda tr(eps) I + 2 mu eps, eps = sym(F) - I  (small strain;
//                             the reference, and not objective: a rotation strains it)
//   Saint Venant-Kirchhoff    psi = lambda/2 (tr E)^2 + mu tr(E^2),   E = (C - I)/2
//   neo-Hookean               psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2
//   neo-Hookean, nearly
//   incompressible            psi = mu/2 (J^-2/3 I1 - 3) + U(J)
//   Mooney-Rivlin             psi = c10 (J^-2/3 I1 - 3) + c01 (J^-4/3 I2 - 3) + U(J)
// All reduce to the linear elastic tangent at F = I (tests check it), with lambda = kappa - 2mu/3
// for the decoupled models and mu = 2 (c10 + c01) for Mooney-Rivlin.
#pragma once

#include <deal.II/base/tensor.h>

#include <array>
#include <memory>
#include <string>

#include "config/scene.h"

namespace fetouch::fem {

using Tensor2 = dealii::Tensor<2, 3>;
using Tensor4 = dealii::Tensor<4, 3>;

// The tangent of the models without I2 (neo-Hookean, coupled and decoupled; linear elasticity with
// H = I) in five scalars and H = F^-T:
//   A_iJkL = alpha d_ik d_JL + zeta F_iJ F_kL + beta H_iJ H_kL + gamma H_iL H_kJ + eta (F_iJ H_kL + H_iJ F_kL).
// The assembly contracts it with the base functions' gradients directly (K_(a,i)(b,k) needs F grad N
// and H grad N of each base function, not the 81 entries of A): the assembly's hot loop.
struct SplitTangent {
  double alpha = 0, zeta = 0, beta = 0, gamma = 0, eta = 0;
  Tensor2 H;
};

class Material {
 public:
  virtual ~Material() = default;
  virtual std::string name() const = 0;
  // psi(F); +infinity where J <= 0 (an inverted element has no energy a solver may accept).
  virtual double energy(const Tensor2& F) const = 0;
  // P(F) and, if `tangent` is not null, A(F). Returns false (and leaves them unset) if J <= 0.
  virtual bool evaluate(const Tensor2& F, Tensor2& stress, Tensor4* tangent) const = 0;
  // Whether evaluate_split() applies; P(F) and the split tangent, which equals evaluate()'s A
  // (tests check it). False (and nothing set) if J <= 0; throws std::logic_error without a split.
  virtual bool has_split_tangent() const { return false; }
  virtual bool evaluate_split(const Tensor2& F, Tensor2& stress, SplitTangent& tangent) const;
  // The small-strain shear modulus and the bulk modulus: for time steps, penalties, scaling.
  virtual double shear_modulus() const = 0;
  virtual double bulk_modulus() const = 0;
  // For the decoupled models psi = psi_iso(J^-2/3 C) + U(J): U'(J) and U''(J) (the mean-dilatation
  // formulation replaces U(J) by U of the element's volume ratio). False for the coupled models.
  virtual bool volumetric(double /*j*/, double& /*u1*/, double& /*u2*/) const { return false; }
};

class LinearElastic final : public Material {
 public:
  LinearElastic(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "linear_elastic"; }
  double energy(const Tensor2& F) const override;
  bool evaluate(const Tensor2& F, Tensor2& stress, Tensor4* tangent) const override;
  bool has_split_tangent() const override { return true; }
  bool evaluate_split(const Tensor2& F, Tensor2& stress, SplitTangent& tangent) const override;
  double shear_modulus() const override { return mu_; }
  double bulk_modulus() const override { return lambda_ + 2 * mu_ / 3; }

 private:
  double lambda_, mu_;
};

// psi and its derivatives in (I1, I2, J): d = [psi_1, psi_2, psi_J], h the symmetric Hessian.
struct InvariantDerivatives {
  double psi = 0;
  std::array<double, 3> d{0, 0, 0};
  std::array<std::array<double, 3>, 3> h{{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}};
};

class InvariantMaterial : public Material {
 public:
  double energy(const Tensor2& F) const override;
  bool evaluate(const Tensor2& F, Tensor2& stress, Tensor4* tangent) const override;
  // The model itself: psi and its partial derivatives at (I1, I2, J), J > 0.
  virtual InvariantDerivatives derivatives(double i1, double i2, double j) const = 0;

 protected:
  // evaluate_split() for the models whose psi has no I2 (psi_2 = 0 and no I2 in the Hessian): the
  // subclasses that are such a model call it. Whether a model is one is a property of its formula, checked
  // by the tests (Materials.SplitTangentRebuildsTheFullTangent) and by an assertion in debug builds, not
  // at every quadrature point.
  bool split_without_i2(const Tensor2& F, Tensor2& stress, SplitTangent& tangent) const;
};

class SaintVenantKirchhoff final : public InvariantMaterial {
 public:
  SaintVenantKirchhoff(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "saint_venant_kirchhoff"; }
  InvariantDerivatives derivatives(double i1, double i2, double j) const override;
  double shear_modulus() const override { return mu_; }
  double bulk_modulus() const override { return lambda_ + 2 * mu_ / 3; }

 private:
  double lambda_, mu_;
};

class NeoHookean final : public InvariantMaterial {
 public:
  NeoHookean(double lambda, double mu) : lambda_(lambda), mu_(mu) {}
  std::string name() const override { return "neo_hookean"; }
  InvariantDerivatives derivatives(double i1, double i2, double j) const override;
  bool has_split_tangent() const override { return true; }
  bool evaluate_split(const Tensor2& F, Tensor2& stress, SplitTangent& tangent) const override {
    return split_without_i2(F, stress, tangent);
  }
  double shear_modulus() const override { return mu_; }
  double bulk_modulus() const override { return lambda_ + 2 * mu_ / 3; }

 private:
  double lambda_, mu_;
};

// The decoupled (isochoric + volumetric) models, for nearly incompressible tissue.
class NearlyIncompressibleNeoHookean final : public InvariantMaterial {
 public:
  NearlyIncompressibleNeoHookean(double kappa, double mu) : kappa_(kappa), mu_(mu) {}
  std::string name() const override { return "neo_hookean_incompressible"; }
  InvariantDerivatives derivatives(double i1, double i2, double j) const override;
  bool has_split_tangent() const override { return true; }
  bool evaluate_split(const Tensor2& F, Tensor2& stress, SplitTangent& tangent) const override {
    return split_without_i2(F, stress, tangent);
  }
  double shear_modulus() const override { return mu_; }
  double bulk_modulus() const override { return kappa_; }
  bool volumetric(double j, double& u1, double& u2) const override;

 private:
  double kappa_, mu_;
};

class MooneyRivlin final : public InvariantMaterial {
 public:
  MooneyRivlin(double c10, double c01, double kappa) : c10_(c10), c01_(c01), kappa_(kappa) {}
  std::string name() const override { return "mooney_rivlin"; }
  InvariantDerivatives derivatives(double i1, double i2, double j) const override;
  double shear_modulus() const override { return 2 * (c10_ + c01_); }
  double bulk_modulus() const override { return kappa_; }
  bool volumetric(double j, double& u1, double& u2) const override;

 private:
  double c10_, c01_, kappa_;
};

// Lame constants from Young's modulus and Poisson's ratio.
double lame_lambda(double youngs_modulus, double poisson_ratio);
double lame_mu(double youngs_modulus, double poisson_ratio);

// The scene's material.
std::unique_ptr<Material> make_material(const config::Material& settings);

}  // namespace fetouch::fem

#include "fem/material.h"

#include <deal.II/base/tensor.h>

#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fetouch::fem {

namespace {

constexpr int dim = 3;
inline double delta(int a, int b) { return a == b ? 1.0 : 0.0; }

Tensor2 identity() {
  Tensor2 i;
  for (int a = 0; a < dim; ++a) i[a][a] = 1;
  return i;
}

}  // namespace

double lame_lambda(double e, double nu) { return e * nu / ((1 + nu) * (1 - 2 * nu)); }
double lame_mu(double e, double nu) { return e / (2 * (1 + nu)); }

// ---- linear elastic ------------------------------------------------------------------------------

double LinearElastic::energy(const Tensor2& F) const {
  const Tensor2 eps = 0.5 * (F + dealii::transpose(F)) - identity();
  const double tr = dealii::trace(eps);
  return 0.5 * lambda_ * tr * tr + mu_ * dealii::scalar_product(eps, eps);
}

bool LinearElastic::evaluate(const Tensor2& F, Tensor2& P, Tensor4* A) const {
  const Tensor2 eps = 0.5 * (F + dealii::transpose(F)) - identity();
  P = lambda_ * dealii::trace(eps) * identity() + 2 * mu_ * eps;
  if (A)
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j)
        for (int k = 0; k < dim; ++k)
          for (int l = 0; l < dim; ++l)
            (*A)[i][j][k][l] = lambda_ * delta(i, j) * delta(k, l) + mu_ * (delta(i, k) * delta(j, l) + delta(i, l) * delta(j, k));
  return true;
}

bool Material::evaluate_split(const Tensor2&, Tensor2&, SplitTangent&) const {
  throw std::logic_error(name() + " has no split tangent");
}

// lambda d_iJ d_kL + mu (d_ik d_JL + d_iL d_kJ): H = I, beta = lambda, alpha = gamma = mu.
bool LinearElastic::evaluate_split(const Tensor2& F, Tensor2& P, SplitTangent& t) const {
  evaluate(F, P, nullptr);
  t = SplitTangent{};
  t.H = identity();
  t.alpha = mu_, t.beta = lambda_, t.gamma = mu_;
  return true;
}

// ---- isotropic hyperelasticity in invariants ---------------------------------------------------

double InvariantMaterial::energy(const Tensor2& F) const {
  const double j = dealii::determinant(F);
  if (!(j > 0)) return std::numeric_limits<double>::infinity();
  const Tensor2 c = dealii::transpose(F) * F;
  const double i1 = dealii::trace(c), i2 = 0.5 * (i1 * i1 - dealii::scalar_product(c, c));
  return derivatives(i1, i2, j).psi;
}

bool InvariantMaterial::evaluate(const Tensor2& F, Tensor2& P, Tensor4* A) const {
  const double j = dealii::determinant(F);
  if (!(j > 0)) return false;
  const Tensor2 c = dealii::transpose(F) * F, b = F * dealii::transpose(F);
  const Tensor2 f_inv_t = dealii::transpose(dealii::invert(F));
  const double i1 = dealii::trace(c), i2 = 0.5 * (i1 * i1 - dealii::scalar_product(c, c));
  const InvariantDerivatives d = derivatives(i1, i2, j);
  const Tensor2 fc = F * c;
  const std::array<Tensor2, 3> g{2 * F, 2 * (i1 * F - fc), j * f_inv_t};  // dI1, dI2, dJ by dF
  P = d.d[0] * g[0] + d.d[1] * g[1] + d.d[2] * g[2];
  if (!A) return true;
  // A = sum_pq h_pq g_p x g_q + psi_1 d2I1 + psi_2 d2I2 + psi_J d2J, built term by term and only
  // from the terms a model has (a neo-Hookean solid has no I2 and one Hessian entry): the hot loop
  // of every assembly.
  Tensor4& a = *A;
  const double jd = d.d[2] * j;
  for (int i = 0; i < dim; ++i)
    for (int J = 0; J < dim; ++J)
      for (int k = 0; k < dim; ++k)
        for (int L = 0; L < dim; ++L) a[i][J][k][L] = jd * (f_inv_t[i][J] * f_inv_t[k][L] - f_inv_t[i][L] * f_inv_t[k][J]);
  for (int p = 0; p < 3; ++p) {
    if (d.h[p][0] == 0 && d.h[p][1] == 0 && d.h[p][2] == 0) continue;
    const Tensor2 hg = d.h[p][0] * g[0] + d.h[p][1] * g[1] + d.h[p][2] * g[2];
    for (int i = 0; i < dim; ++i)
      for (int J = 0; J < dim; ++J)
        for (int k = 0; k < dim; ++k)
          for (int L = 0; L < dim; ++L) a[i][J][k][L] += g[p][i][J] * hg[k][L];
  }
  const double d1 = d.d[1];
  if (d1 != 0)
    for (int i = 0; i < dim; ++i)
      for (int J = 0; J < dim; ++J)
        for (int k = 0; k < dim; ++k)
          for (int L = 0; L < dim; ++L)
            a[i][J][k][L] += d1 * (4 * F[i][J] * F[k][L] - 2 * delta(i, k) * c[L][J] - 2 * F[i][L] * F[k][J] -
                                   2 * b[i][k] * delta(J, L));
  const double diagonal = 2 * d.d[0] + 2 * i1 * d1;  // the d_ik d_JL terms of d2I1 and d2I2
  for (int i = 0; i < dim; ++i)
    for (int J = 0; J < dim; ++J) a[i][J][i][J] += diagonal;
  return true;
}

// With psi_2 = 0: P = 2 psi_1 F + psi_J J H, and A = 2 psi_1 d_ik d_JL + 4 h_11 F x F
// + 2 J h_1J (F x H + H x F) + (J^2 h_JJ + J psi_J) H x H - J psi_J H_iL H_kJ (H = F^-T).
bool InvariantMaterial::split_without_i2(const Tensor2& F, Tensor2& P, SplitTangent& t) const {
  const double j = dealii::determinant(F);
  if (!(j > 0)) return false;
  const Tensor2 c = dealii::transpose(F) * F;
  const double i1 = dealii::trace(c), i2 = 0.5 * (i1 * i1 - dealii::scalar_product(c, c));
  const InvariantDerivatives d = derivatives(i1, i2, j);
  assert(d.d[1] == 0 && d.h[0][1] == 0 && d.h[1][1] == 0 && d.h[1][2] == 0);  // the model has no I2
  t.H = dealii::transpose(dealii::invert(F));
  P = 2 * d.d[0] * F + d.d[2] * j * t.H;
  t.alpha = 2 * d.d[0];
  t.zeta = 4 * d.h[0][0];
  t.eta = 2 * j * d.h[0][2];
  t.beta = j * j * d.h[2][2] + j * d.d[2];
  t.gamma = -j * d.d[2];
  return true;
}

InvariantDerivatives SaintVenantKirchhoff::derivatives(double i1, double i2, double) const {
  // tr E = (I1 - 3)/2, tr E^2 = (I1^2 - 2 I2 - 2 I1 + 3)/4.
  InvariantDerivatives r;
  r.psi = lambda_ / 8 * (i1 - 3) * (i1 - 3) + mu_ / 4 * (i1 * i1 - 2 * i2 - 2 * i1 + 3);
  r.d = {lambda_ / 4 * (i1 - 3) + mu_ / 2 * (i1 - 1), -mu_ / 2, 0};
  r.h[0][0] = lambda_ / 4 + mu_ / 2;
  return r;
}

InvariantDerivatives NeoHookean::derivatives(double i1, double, double j) const {
  const double log_j = std::log(j);
  InvariantDerivatives r;
  r.psi = mu_ / 2 * (i1 - 3) - mu_ * log_j + lambda_ / 2 * log_j * log_j;
  r.d = {mu_ / 2, 0, (-mu_ + lambda_ * log_j) / j};
  r.h[2][2] = (mu_ + lambda_ - lambda_ * log_j) / (j * j);
  return r;
}

namespace {
// U(J) = kappa/4 (J^2 - 1 - 2 ln J) and its first two derivatives.
void volumetric_energy(double kappa, double j, InvariantDerivatives& r) {
  r.psi += kappa / 4 * (j * j - 1 - 2 * std::log(j));
  r.d[2] += kappa / 2 * (j - 1 / j);
  r.h[2][2] += kappa / 2 * (1 + 1 / (j * j));
}
}  // namespace

bool NearlyIncompressibleNeoHookean::volumetric(double j, double& u1, double& u2) const {
  InvariantDerivatives r;
  volumetric_energy(kappa_, j, r);
  u1 = r.d[2], u2 = r.h[2][2];
  return true;
}

bool MooneyRivlin::volumetric(double j, double& u1, double& u2) const {
  InvariantDerivatives r;
  volumetric_energy(kappa_, j, r);
  u1 = r.d[2], u2 = r.h[2][2];
  return true;
}

InvariantDerivatives NearlyIncompressibleNeoHookean::derivatives(double i1, double, double j) const {
  const double j23 = std::pow(j, -2.0 / 3), j53 = j23 / j, j83 = j53 / j;
  InvariantDerivatives r;
  r.psi = mu_ / 2 * (j23 * i1 - 3);
  r.d = {mu_ / 2 * j23, 0, -mu_ / 3 * j53 * i1};
  r.h[0][2] = r.h[2][0] = -mu_ / 3 * j53;
  r.h[2][2] = 5 * mu_ / 9 * j83 * i1;
  volumetric_energy(kappa_, j, r);
  return r;
}

InvariantDerivatives MooneyRivlin::derivatives(double i1, double i2, double j) const {
  const double j23 = std::pow(j, -2.0 / 3), j43 = j23 * j23;
  InvariantDerivatives r;
  r.psi = c10_ * (j23 * i1 - 3) + c01_ * (j43 * i2 - 3);
  r.d = {c10_ * j23, c01_ * j43, -2.0 / 3 * c10_ * j23 / j * i1 - 4.0 / 3 * c01_ * j43 / j * i2};
  r.h[0][2] = r.h[2][0] = -2.0 / 3 * c10_ * j23 / j;
  r.h[1][2] = r.h[2][1] = -4.0 / 3 * c01_ * j43 / j;
  r.h[2][2] = 10.0 / 9 * c10_ * j23 / (j * j) * i1 + 28.0 / 9 * c01_ * j43 / (j * j) * i2;
  volumetric_energy(kappa_, j, r);
  return r;
}

std::unique_ptr<Material> make_material(const config::Material& m) {
  using config::MaterialModel;
  const double e = m.youngs_modulus_pa, nu = m.poisson_ratio;
  switch (m.model) {
    case MaterialModel::linear_elastic: return std::make_unique<LinearElastic>(lame_lambda(e, nu), lame_mu(e, nu));
    case MaterialModel::saint_venant_kirchhoff:
      return std::make_unique<SaintVenantKirchhoff>(lame_lambda(e, nu), lame_mu(e, nu));
    case MaterialModel::neo_hookean: return std::make_unique<NeoHookean>(lame_lambda(e, nu), lame_mu(e, nu));
    case MaterialModel::neo_hookean_incompressible:
      return std::make_unique<NearlyIncompressibleNeoHookean>(e / (3 * (1 - 2 * nu)), lame_mu(e, nu));
    case MaterialModel::mooney_rivlin: return std::make_unique<MooneyRivlin>(m.c10_pa, m.c01_pa, m.bulk_modulus_pa);
  }
  throw std::invalid_argument("unknown material model");
}

}  // namespace fetouch::fem

#include "fem/condensed_compliance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fem/small_spd.h"

namespace fetouch::fem {

using namespace dealii;

namespace {

// C = (B'K B)^-1 (H B)' (SmallSpd: directions that have become dependent are left out); NaN where
// B'K B has a diagonal entry that is not positive (K not positive definite there).
FullMatrix<double> galerkin_coefficients(const FullMatrix<double>& gram, const FullMatrix<double>& hb) {
  const unsigned int size = gram.m(), columns = hb.m();
  FullMatrix<double> c(size, columns);
  std::vector<double> g(std::size_t(size) * size), b(size), x(size);
  for (unsigned int a = 0; a < size; ++a)
    for (unsigned int j = 0; j < size; ++j) g[a * size + j] = gram(a, j);
  SmallSpd spd;
  const bool ok = spd.factorise(g, size);
  for (unsigned int k = 0; k < columns; ++k) {
    for (unsigned int a = 0; a < size; ++a) b[a] = hb(k, a);
    if (ok) spd.solve(b.data(), x.data());
    for (unsigned int a = 0; a < size; ++a) c(a, k) = ok ? x[a] : std::numeric_limits<double>::quiet_NaN();
  }
  return c;
}

}  // namespace

// The last compliance's columns span the answer almost exactly when the state moved little: the
// Galerkin solution in their span, z = Z C with (Z'K Z) C = Z'H', costs 3m products with K and no
// solve. Its residual R = H' - K Z C bounds the error of W = H Z C (which is R'K^-1 R, quadratic in
// R). While R exceeds the Galerkin tolerance, the span grows by the preconditioned residuals P^-1 R (one
// blocked application of the factorisation, which reduces R as a CG step would) and the Galerkin
// solution is taken again (a block Krylov iteration preconditioned by the factorisation); a first
// compliance, or one that does not get there in kMaxGalerkinRounds rounds, solves each column to
// kComplianceTolerance.
FullMatrix<double> CondensedCompliance::compute(LinearSystem& system, const std::vector<Vector<double>>& h,
                                                ComplianceTimes& times) {
  const unsigned int columns = static_cast<unsigned int>(h.size());
  const std::size_t n = h.empty() ? 0 : h[0].size();
  const int factorisations = system.tangent().factorisations();
  system.times = LinearSystem::Times();
  std::vector<Vector<double>>& z = z_;
  bool solve_columns = z.size() != columns;
  double worst = std::numeric_limits<double>::infinity();
  // The basis B and K B: the first round replaces the old columns by their Galerkin combination Z
  // (K Z = H' - R comes for free); each round then adds P^-1 R, at the cost of 3m products with K
  // and one blocked application of the factorisation.
  std::vector<Vector<double>> basis = z;
  // With a liquid's rank-one part c g g' (c ~ 10^13) in the operator, a basis vector's component
  // along g weighs c (g'b)^2 in B'(K + c g g')B and drowns the K part there: the projection loses
  // its digits and the rounds stall (the default replay's presses took 4-7 rounds, a first touch 6
  // and then solved its columns). So every basis vector is made g-free, b - (g'b / g'w) w, and
  // the carrier w = (P + c g g')^-1 g, the one direction along g, joins the basis once.
  // Deflation makes b g-free for any w with g'w != 0, so the carrier is kept from the frame before
  // (computing it is a solve with the factorisation: 43 of a 78 ms frame on the anatomy at 3.6 mm).
  // The first round that applies the factorisation anyway brings P^-1 g up to date and with it a
  // fresh carrier, which then replaces the kept one in the basis.
  const Vector<double>* g = system.rank_one_c() != 0 ? system.rank_one_g() : nullptr;
  Vector<double>& carrier = carrier_;
  if (!g || carrier.size() != n) carrier.reinit(0);
  bool carrier_fresh = false, carrier_used = false;
  double g_carrier = 0;  // g'w
  const auto deflate = [&](Vector<double>& b) {
    if (g) b.add(-(*g * b) / g_carrier, carrier);
  };
  std::size_t carrier_index = 0;
  times.recycled_directions = 0;
  if (g && !basis.empty()) {
    // A kept carrier that has turned away from g (its cosine with g under half what it was) is
    // replaced at once: the deflation divides by g'w.
    const auto cosine = [&] { return (*g * carrier) / (g->l2_norm() * carrier.l2_norm()); };
    if (carrier.size() == 0 || !(cosine() > carrier_cosine_ / 2)) {
      system.apply_factorisation_to_rank_one_g(carrier), carrier_fresh = true;
      carrier_cosine_ = cosine();
    }
    g_carrier = *g * carrier;
    for (Vector<double>& b : basis) deflate(b);
    carrier_index = basis.size();
    basis.push_back(carrier);
    carrier_used = true;
  }
  std::vector<Vector<double>> kb(basis.size(), Vector<double>(n));
  system.multiply(basis, kb);
  // B'K B and H B, grown by the new directions' rows and columns each round (entries below `known`
  // hold; B'K B taken symmetric, as it is).
  FullMatrix<double> gram, hb;
  unsigned int known = 0;
  // The directions the last compliance's rounds added (where the factorisation missed K then) join
  // the span, at the cost of products with K only, when the old columns alone do not do.
  bool recycled = recycled_.empty();
  std::vector<std::size_t> added;  // where this compliance's rounds' directions are in the basis
  for (int round = 0; !solve_columns;) {
    const unsigned int size = static_cast<unsigned int>(basis.size());
    FullMatrix<double> grown(size, size), hb_grown(columns, size);
    for (unsigned int a = 0; a < size; ++a)
      for (unsigned int b = a; b < size; ++b)
        grown(a, b) = grown(b, a) = b < known ? gram(a, b) : basis[a] * kb[b];
    for (unsigned int a = 0; a < columns; ++a)
      for (unsigned int b = 0; b < size; ++b) hb_grown(a, b) = b < known ? hb(a, b) : h[a] * basis[b];
    gram = grown, hb = hb_grown, known = size;
    const FullMatrix<double> c = galerkin_coefficients(gram, hb);
    std::vector<double> residuals(n * columns);  // column-major, for the blocked solve
    std::vector<Vector<double>> kz(columns, Vector<double>(n));
    worst = 0;
    for (unsigned int k = 0; k < columns; ++k) {
      z[k] = 0;
      for (unsigned int j = 0; j < size; ++j) {
        z[k].add(c(j, k), basis[j]);
        kz[k].add(c(j, k), kb[j]);
      }
      Vector<double> residual = h[k];
      residual -= kz[k];
      const double relative = residual.l2_norm() / h[k].l2_norm();
      worst = std::isnan(relative) ? relative : std::max(worst, relative);  // a singular B'K B: NaN, kept
      std::copy(residual.begin(), residual.end(), residuals.begin() + std::size_t(k) * n);
    }
    if (worst <= galerkin_tolerance) break;
    if (!std::isfinite(worst) || round == kMaxGalerkinRounds) {
      solve_columns = true;
      break;
    }
    if (!recycled) {
      recycled = true;
      std::vector<Vector<double>> kr(recycled_.size(), Vector<double>(n));
      for (Vector<double>& r : recycled_) deflate(r);
      system.multiply(recycled_, kr);
      for (std::size_t k = 0; k < recycled_.size(); ++k) basis.push_back(recycled_[k]), kb.push_back(std::move(kr[k]));
      times.recycled_directions = static_cast<int>(recycled_.size());
      continue;
    }
    ++round;
    std::vector<double> corrections(residuals.size());
    system.apply_factorisation(residuals.data(), corrections.data(), static_cast<int>(columns));
    if (g && !carrier_fresh) {  // P^-1 g is current now: the fresh carrier costs no solve
      system.apply_factorisation_to_rank_one_g(carrier);
      carrier_fresh = true;
      g_carrier = *g * carrier;
      carrier_cosine_ = g_carrier / (g->l2_norm() * carrier.l2_norm());
      basis[carrier_index] = carrier;
      system.multiply(carrier, kb[carrier_index]);
      for (unsigned int a = 0; a < known; ++a)  // its row and column of B'K B and H B
        gram(a, carrier_index) = gram(carrier_index, a) = basis[a] * kb[carrier_index];
      for (unsigned int k = 0; k < columns; ++k) hb(k, carrier_index) = h[k] * basis[carrier_index];
    }
    // The span keeps every direction so far (a block Krylov space): the Galerkin solution in it is
    // the best in the energy norm, as block CG's would be.
    if (round == 1 && !g && basis.size() == columns)  // (with a liquid, z is not g-free)
      basis = z, kb = std::move(kz), known = 0;
    std::vector<Vector<double>> d(columns, Vector<double>(n)), kd(columns, Vector<double>(n));
    for (unsigned int k = 0; k < columns; ++k) {
      std::copy_n(corrections.begin() + std::size_t(k) * n, n, d[k].begin());
      system.constraints().distribute(d[k]);
      deflate(d[k]);
    }
    system.multiply(d, kd);
    for (unsigned int k = 0; k < columns; ++k) {
      added.push_back(basis.size());
      basis.push_back(std::move(d[k])), kb.push_back(std::move(kd[k]));
    }
  }
  // The newest directions first, then the kept ones, at most kRecycledPerColumn per column (the
  // basis is not used after this).
  std::vector<Vector<double>> kept;
  for (auto k = added.rbegin(); k != added.rend(); ++k) kept.push_back(std::move(basis[*k]));
  for (Vector<double>& r : recycled_) kept.push_back(std::move(r));
  if (kept.size() > kRecycledPerColumn * columns) kept.resize(kRecycledPerColumn * columns);
  recycled_ = std::move(kept);
  times.galerkin_residual = std::isfinite(worst) ? worst : 0;
  if (solve_columns) {
    const bool warm = z.size() == columns;
    if (!warm) z.assign(columns, Vector<double>(n));
    // A first compliance to kComplianceTolerance; a frame's, whose Galerkin update failed, to the
    // residual the update would have accepted (its error in W is of the same order).
    const double tolerance = warm ? std::max(kComplianceTolerance, galerkin_tolerance) : kComplianceTolerance;
    for (unsigned int k = 0; k < columns; ++k) system.solve(h[k], z[k], tolerance, /*zero_guess=*/!warm);
  }
  times.refined = solve_columns;
  times.carrier_kept = carrier_used && !carrier_fresh;
  times.factorisation_s = system.times.factorisation_s;
  times.solves_s = system.times.solve_s;
  times.linear_iterations = system.times.linear_iterations;
  times.factorisations = system.tangent().factorisations() - factorisations;
  FullMatrix<double> w(columns, columns);
  for (unsigned int a = 0; a < columns; ++a)
    for (unsigned int b = 0; b < columns; ++b) w(a, b) = h[a] * z[b];
  // W is symmetric; the solves leave an asymmetry of the order of their tolerance.
  for (unsigned int a = 0; a < columns; ++a)
    for (unsigned int b = 0; b < a; ++b) w(a, b) = w(b, a) = (w(a, b) + w(b, a)) / 2;
  return w;
}

}  // namespace fetouch::fem

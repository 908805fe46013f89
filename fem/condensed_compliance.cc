#include "fem/condensed_compliance.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <deal.II/lac/lapack_templates.h>

#include "fem/small_spd.h"
#include "fem/stopwatch.h"

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

double* CondensedCompliance::Columns::add() {
  if ((count_ + 1) * n_ > data_.size()) data_.resize(std::max(2 * data_.size(), (count_ + 1) * n_));
  return (*this)[count_++];
}

void CondensedCompliance::Columns::resize(std::size_t count) {
  if (count * n_ > data_.size()) data_.resize(std::max(2 * data_.size(), count * n_));
  count_ = count;
}

namespace {

using Int = types::blas_int;

double dot(const double* a, const double* b, std::size_t n) {
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += a[i] * b[i];
  return sum;
}

// out (rows x cols, column-major, leading dimension rows) = A' B[:, first..first+cols), A and B
// n x (something) column-major: the entries a . b of a block of columns, in one matrix product.
void inner_products(const double* a, Int rows, const double* b, Int cols, Int n, std::vector<double>& out) {
  out.resize(std::size_t(rows) * std::size_t(cols));
  if (rows == 0 || cols == 0) return;
  const double one = 1, zero = 0;
  gemm("T", "N", &rows, &cols, &n, &one, a, &n, b, &n, &zero, out.data(), &rows);
}

// Y (n x cols) = X (n x k) C (k x cols), all column-major.
void combine(const double* x, Int k, const double* c, Int cols, Int n, double* y) {
  const double one = 1, zero = 0;
  if (k == 0) {
    std::fill(y, y + std::size_t(n) * std::size_t(cols), 0.0);
    return;
  }
  gemm("N", "N", &n, &cols, &k, &one, x, &n, c, &k, &zero, y, &n);
}

}  // namespace

// The last compliance's columns span the answer almost exactly when the state moved little: the
// Galerkin solution in their span, z = Z C with (Z'K Z) C = Z'H', costs 3m products with K and no
// solve. Its residual R = H' - K Z C bounds the error of W = H Z C (which is R'K^-1 R, quadratic in
// R). While R exceeds the Galerkin tolerance, the span grows by the preconditioned residuals P^-1 r of
// the columns that miss it (one blocked application of the factorisation, which reduces R as a CG
// step would; a column within the tolerance gets no direction, which would cost a product with K in
// this and every later round: 15.2 products an update at 31,878 DOFs became 9.9) and the Galerkin
// solution is taken again (a block Krylov iteration preconditioned by the factorisation); a first
// compliance, or one that does not get there in kMaxGalerkinRounds rounds, solves each column to
// kComplianceTolerance. The basis B, K B and H are kept side by side (Columns), so that B'K B, H B
// and B C are matrix products: vector by vector they took 30 of a 71 ms update at 52,650 DOFs.
FullMatrix<double> CondensedCompliance::compute(LinearSystem& system, const std::vector<Vector<double>>& h,
                                                ComplianceTimes& times) {
  const unsigned int columns = static_cast<unsigned int>(h.size());
  const std::size_t n = h.empty() ? 0 : h[0].size();
  const Int rows = static_cast<Int>(n);
  const int factorisations = system.tangent().factorisations();
  system.times = LinearSystem::Times();
  std::vector<Vector<double>>& z = z_;
  bool solve_columns = z.size() != columns;
  double worst = std::numeric_limits<double>::infinity();
  if (recycled_.length() != n) recycled_.reset(n), recycled_column_.clear();
  // The basis B and K B: the first round replaces the old columns by their Galerkin combination Z
  // (K Z = H' - R comes for free); each round then adds P^-1 r of the columns that miss, at the
  // cost of a product with K each and one blocked application of the factorisation.
  Columns& basis = basis_;
  Columns& kb = kb_;
  basis.reset(n), kb.reset(n), h_.reset(n);
  std::vector<double> h_norms(columns);
  for (unsigned int k = 0; k < columns; ++k) std::copy(h[k].begin(), h[k].end(), h_.add()), h_norms[k] = h[k].l2_norm();
  if (!solve_columns)
    for (const Vector<double>& old : z) std::copy(old.begin(), old.end(), basis.add());
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
  const auto deflate = [&](double* b) {
    if (!g) return;
    const double along = dot(g->begin(), b, n) / g_carrier;
    const double* w = carrier.begin();
    for (std::size_t i = 0; i < n; ++i) b[i] -= along * w[i];
  };
  std::size_t carrier_index = 0;
  times.recycled_directions = 0;
  times.first_residual = 0;
  times.rounds = 0, times.new_directions = 0;
  if (g && basis.count() > 0) {
    // A kept carrier that has turned away from g (its cosine with g under half what it was) is
    // replaced at once: the deflation divides by g'w.
    const auto cosine = [&] { return (*g * carrier) / (g->l2_norm() * carrier.l2_norm()); };
    if (carrier.size() == 0 || !(cosine() > carrier_cosine_ / 2)) {
      system.apply_factorisation_to_rank_one_g(carrier), carrier_fresh = true;
      carrier_cosine_ = cosine();
    }
    g_carrier = *g * carrier;
    for (std::size_t b = 0; b < basis.count(); ++b) deflate(basis[b]);
    carrier_index = basis.count();
    std::copy(carrier.begin(), carrier.end(), basis.add());
    carrier_used = true;
  }
  // K times the basis columns from `first` on, into kb's columns of the same index.
  std::vector<const double*> in;
  std::vector<double*> out;
  times.products = 0, times.products_s = 0;
  const auto multiply = [&](const double* const* x, double* const* y, int count) {
    const auto start = std::chrono::steady_clock::now();
    system.multiply(x, y, count);
    times.products += count;
    times.products_s += seconds_since(start);
  };
  const auto multiply_from = [&](std::size_t first) {
    kb.resize(basis.count());
    in.clear(), out.clear();
    for (std::size_t j = first; j < basis.count(); ++j) in.push_back(basis[j]), out.push_back(kb[j]);
    multiply(in.data(), out.data(), static_cast<int>(in.size()));
  };
  multiply_from(0);
  // B'K B and H B, grown by the new directions' rows and columns each round (entries below `known`
  // hold; B'K B taken symmetric, as it is).
  FullMatrix<double> gram, hb;
  unsigned int known = 0;
  std::vector<double> products, c_block, residuals, corrections;
  std::vector<unsigned int> missing;  // the columns whose residual is above the tolerance
  // The directions the last compliance's rounds added (where the factorisation missed K then) for
  // the columns that miss now join the span, at the cost of products with K only, when the old
  // columns alone do not do.
  bool recycled = recycled_.count() == 0;
  std::vector<std::pair<std::size_t, unsigned int>> added;  // this compliance's rounds' directions: where, whose
  bool first_pass = true;          // the old columns (and the carrier) alone in the basis
  unsigned int c_size = 0;         // the basis vectors the last Galerkin coefficients C are for
  const auto z_from_basis = [&] {  // z_block_ = B C
    z_block_.reset(n), z_block_.resize(columns);
    combine(basis[0], static_cast<Int>(c_size), c_block.data(), static_cast<Int>(columns), rows, z_block_[0]);
  };
  for (int round = 0; !solve_columns;) {
    const unsigned int size = static_cast<unsigned int>(basis.count());
    const Int fresh = static_cast<Int>(size - known);
    FullMatrix<double> grown(size, size), hb_grown(columns, size);
    for (unsigned int a = 0; a < known; ++a)
      for (unsigned int b = 0; b < known; ++b) grown(a, b) = gram(a, b);
    inner_products(basis[0], static_cast<Int>(size), kb[known], fresh, rows, products);  // B'(K B_new)
    for (unsigned int b = known; b < size; ++b)
      for (unsigned int a = 0; a <= b; ++a) grown(a, b) = grown(b, a) = products[std::size_t(b - known) * size + a];
    for (unsigned int a = 0; a < columns; ++a)
      for (unsigned int b = 0; b < known; ++b) hb_grown(a, b) = hb(a, b);
    inner_products(h_[0], static_cast<Int>(columns), basis[known], fresh, rows, products);  // H B_new
    for (unsigned int b = known; b < size; ++b)
      for (unsigned int a = 0; a < columns; ++a) hb_grown(a, b) = products[std::size_t(b - known) * columns + a];
    gram = grown, hb = hb_grown, known = size;
    const FullMatrix<double> c = galerkin_coefficients(gram, hb);
    c_block.resize(std::size_t(size) * columns);  // C column-major
    for (unsigned int k = 0; k < columns; ++k)
      for (unsigned int j = 0; j < size; ++j) c_block[std::size_t(k) * size + j] = c(j, k);
    c_size = size;
    // K Z = (K B) C for the residuals; Z = B C itself only once the rounds end (z_from_basis), as
    // a round does not need it and it streams the whole basis again (the Leopold exercise's good
    // take, 564 updates, up to 6 rounds over some 60 vectors while the hands slide: the Galerkin
    // coefficients and these products 554-557 ms in all before, 308-318 ms after).
    kz_block_.reset(n), kz_block_.resize(columns);
    combine(kb[0], static_cast<Int>(size), c_block.data(), static_cast<Int>(columns), rows, kz_block_[0]);
    residuals.resize(n * columns);  // the missing columns', column-major, for the blocked solve
    worst = 0;
    missing.clear();
    for (unsigned int k = 0; k < columns; ++k) {
      double* residual = residuals.data() + missing.size() * n;  // overwritten by the next if k passes
      const double* hk = h_[k];
      const double* kzk = kz_block_[k];
      for (std::size_t i = 0; i < n; ++i) residual[i] = hk[i] - kzk[i];
      const double relative = std::sqrt(dot(residual, residual, n)) / h_norms[k];
      worst = std::isnan(relative) ? relative : std::max(worst, relative);  // a singular B'K B: NaN, kept
      if (!(relative <= galerkin_tolerance)) missing.push_back(k);
    }
    if (first_pass) times.first_residual = worst, first_pass = false;  // the old columns' alone
    if (worst <= galerkin_tolerance) break;
    if (!std::isfinite(worst) || round == kMaxGalerkinRounds) {
      solve_columns = true;
      break;
    }
    if (!recycled) {
      recycled = true;
      const std::size_t first = basis.count();
      for (std::size_t k = 0; k < recycled_.count(); ++k) {
        if (std::find(missing.begin(), missing.end(), recycled_column_[k]) == missing.end()) continue;
        deflate(recycled_[k]);
        std::copy(recycled_[k], recycled_[k] + n, basis.add());
      }
      times.recycled_directions = static_cast<int>(basis.count() - first);
      if (basis.count() > first) {
        multiply_from(first);
        continue;
      }
    }
    ++round;
    // Only the columns that miss get new directions: the others' residuals are within the
    // tolerance already (the Galerkin solution in the grown span is at least as good in the energy
    // norm), and each direction costs a product with K now and in every later round.
    const int count = static_cast<int>(missing.size());
    corrections.resize(missing.size() * n);
    system.apply_factorisation(residuals.data(), corrections.data(), count);
    ++times.rounds, times.new_directions += count;
    if (g && !carrier_fresh) {  // P^-1 g is current now: the fresh carrier costs no solve
      system.apply_factorisation_to_rank_one_g(carrier);
      carrier_fresh = true;
      g_carrier = *g * carrier;
      carrier_cosine_ = g_carrier / (g->l2_norm() * carrier.l2_norm());
      std::copy(carrier.begin(), carrier.end(), basis[carrier_index]);
      const double* x = basis[carrier_index];
      double* y = kb[carrier_index];
      multiply(&x, &y, 1);
      for (unsigned int a = 0; a < known; ++a)  // its row and column of B'K B and H B
        gram(a, carrier_index) = gram(carrier_index, a) = dot(basis[a], kb[carrier_index], n);
      for (unsigned int k = 0; k < columns; ++k) hb(k, carrier_index) = dot(h_[k], basis[carrier_index], n);
    }
    // The span keeps every direction so far (a block Krylov space): the Galerkin solution in it is
    // the best in the energy norm, as block CG's would be.
    if (round == 1 && !g && basis.count() == columns) {  // (with a liquid, z is not g-free)
      z_from_basis();
      basis.swap(z_block_), kb.swap(kz_block_), known = 0;
      z_block_.reset(n), kz_block_.reset(n);
    }
    const std::size_t first = basis.count();
    scratch_.reinit(n, /*omit_zeroing_entries=*/true);
    for (int k = 0; k < count; ++k) {
      std::copy_n(corrections.begin() + std::size_t(k) * n, n, scratch_.begin());
      system.constraints().distribute(scratch_);
      double* d = basis.add();
      std::copy(scratch_.begin(), scratch_.end(), d);
      deflate(d);
      added.emplace_back(first + k, missing[k]);
    }
    multiply_from(first);
  }
  // The rounds end right after their last Galerkin coefficients: Z = B C (also the start of the
  // columns' solves when they are solved afresh).
  if (c_size > 0) {
    z_from_basis();
    for (unsigned int k = 0; k < columns; ++k) std::copy(z_block_[k], z_block_[k] + n, z[k].begin());
  }
  // The newest directions first, then the kept ones, at most kRecycledPerColumn for each column.
  kept_.reset(n), kept_column_.clear();
  std::vector<std::size_t> per_column(columns);
  const auto keep = [&](const double* d, unsigned int column) {
    if (column >= columns || per_column[column] == kRecycledPerColumn) return;
    ++per_column[column];
    std::copy(d, d + n, kept_.add());
    kept_column_.push_back(column);
  };
  for (auto k = added.rbegin(); k != added.rend(); ++k) keep(basis[k->first], k->second);
  for (std::size_t k = 0; k < recycled_.count(); ++k) keep(recycled_[k], recycled_column_[k]);
  recycled_.swap(kept_), recycled_column_.swap(kept_column_);
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

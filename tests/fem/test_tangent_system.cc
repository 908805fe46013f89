// The tangent's linear solves on matrices with known inverses: a fresh factorisation solves
// directly, a changed matrix is solved by CG on the old factorisation to the requested residual
// without refactoring, a matrix that is not positive definite falls back to LDL' and is still solved.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <utility>
#include <vector>

#include <petscsys.h>

#include <stdexcept>

#include "fem/cholesky_factor.h"
#include "fem/tangent_system.h"

namespace fetouch::fem {
namespace {

// The pattern of a tridiagonal matrix on n unknowns, in compressed sparse rows.
void tridiagonal_pattern(int n, std::vector<int>& start, std::vector<int>& columns) {
  start = {0}, columns.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - 1); j <= std::min(n - 1, i + 1); ++j) columns.push_back(j);
    start.push_back(static_cast<int>(columns.size()));
  }
}

// The 1D Dirichlet Laplacian tridiag(-1, d, -1) on n unknowns.
void tridiagonal(TangentSystem& k, int n, double diagonal) {
  std::vector<int> start, columns;
  tridiagonal_pattern(n, start, columns);
  if (k.rows() != static_cast<std::size_t>(n)) k.set_pattern(start, columns, TangentSystem::Method::factorisation, 0, n);
  k.zero();
  for (int i = 0; i < n; ++i) {
    k.add(i, i, diagonal);
    if (i > 0) k.add(i, i - 1, -1);
    if (i + 1 < n) k.add(i, i + 1, -1);
  }
  k.finish(std::vector<bool>(n, false));
}

double relative_residual(const TangentSystem& k, const std::vector<double>& b, const std::vector<double>& x) {
  std::vector<double> kx(b.size());
  k.multiply(x.data(), kx.data());
  double r = 0, s = 0;
  for (std::size_t i = 0; i < b.size(); ++i) r += (b[i] - kx[i]) * (b[i] - kx[i]), s += b[i] * b[i];
  return std::sqrt(r / s);
}

// tridiag(-1, 3, -1) (eigenvalues in 1..5) factorised in a frame, then 10 % more on the diagonal
// solved in the next frame by CG on the old factorisation (a preconditioned spectrum in 1.06..1.3)
// to `tolerance`, from x = K^-1 b of the first: the first solve's and the drifted solve's counts.
std::pair<TangentSystem::SolveStats, TangentSystem::SolveStats> drift_by_a_tenth(TangentSystem& k, int n, std::vector<double>& b,
                                                                                 std::vector<double>& x, double tolerance) {
  tridiagonal(k, n, 3.0);
  b.assign(n, 0.0), x.assign(n, 0.0);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.1 * i) + 0.5;
  k.begin_frame(true);
  const TangentSystem::SolveStats first = k.solve(b.data(), x.data(), 1e-10, true);
  tridiagonal(k, n, 3.3);
  k.begin_frame(true);
  return {first, k.solve(b.data(), x.data(), tolerance, false)};
}

// After one background factorisation, taken up: it factorised K as it was at the request, which is
// K now, so CG against it takes one iteration.
void expect_the_requested_k_factorised(TangentSystem& k, const std::vector<double>& b, std::vector<double>& x) {
  EXPECT_FALSE(k.background_under_way());
  EXPECT_EQ(k.factorisations(), 2);
  EXPECT_EQ(k.background_factorisations(), 1);
  const TangentSystem::SolveStats fresh = k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_FALSE(fresh.refactored);
  EXPECT_LE(fresh.iterations, 1);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
}

TEST(TangentSystem, SolvesExactlyThenByCgOnTheOldFactorisation) {
  const int n = 200;
  TangentSystem k;
  tridiagonal(k, n, 2.0);
  // K x = b with x_i = sin(pi (i+1)/(n+1)), an eigenvector: b = (2 - 2 cos(pi/(n+1))) x.
  std::vector<double> exact(n), b(n), x(n);
  const double lambda = 2 - 2 * std::cos(M_PI / (n + 1));
  for (int i = 0; i < n; ++i) exact[i] = std::sin(M_PI * (i + 1) / (n + 1)), b[i] = lambda * exact[i];
  const TangentSystem::SolveStats first = k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_TRUE(first.refactored);
  for (int i = 0; i < n; ++i) EXPECT_NEAR(x[i], exact[i], 1e-9);
  // 1 % stiffer: the old factorisation preconditions CG, which must reach the tolerance itself.
  tridiagonal(k, n, 2.02);
  const TangentSystem::SolveStats second = k.solve(b.data(), x.data(), 1e-10, false);
  EXPECT_FALSE(second.refactored);
  EXPECT_GT(second.iterations, 0);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
  EXPECT_EQ(k.factorisations(), 1);
}

// Inside frames a drifted factorisation is not replaced at once: a new one of K as it was when CG
// first needed more than refactor_after_iterations is made in the background and taken up
// swap_after_frames frames later (deterministically here, as lockstep replays run); until then CG
// on the old one carries the solves. After the swap CG against the factorisation of this very K
// takes one iteration.
TEST(TangentSystem, ADriftedFactorisationIsReplacedFromTheBackgroundThreeFramesLater) {
  const int n = 200;
  TangentSystem k;
  k.set_deterministic(true);
  k.background_flops_per_frame = 0;  // the schedule of a factorisation that takes frames
  tridiagonal(k, n, 2.0);
  std::vector<double> b(n), x(n);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.1 * i) + 0.5;
  k.begin_frame(true);
  EXPECT_TRUE(k.solve(b.data(), x.data(), 1e-10, true).refactored);
  ASSERT_EQ(k.factorisations(), 1);
  // 2.05 on the diagonal: the old factorisation's preconditioned spectrum spans 1.01 to about 200.
  tridiagonal(k, n, 2.05);
  k.begin_frame(true);
  const TangentSystem::SolveStats drifted = k.solve(b.data(), x.data(), 1e-10, false);
  EXPECT_FALSE(drifted.refactored);
  EXPECT_GT(drifted.iterations, k.refactor_after_iterations);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
  EXPECT_TRUE(k.background_under_way());
  ASSERT_EQ(k.swap_after_frames, 3);
  for (int frame = 1; frame < 3; ++frame) {
    k.begin_frame(true);
    EXPECT_EQ(k.factorisations(), 1) << "taken up early, frame " << frame;
    EXPECT_TRUE(k.background_under_way());
  }
  k.begin_frame(true);
  EXPECT_EQ(k.factorisations(), 2);
  EXPECT_EQ(k.background_factorisations(), 1);
  EXPECT_FALSE(k.background_under_way());
  const TangentSystem::SolveStats fresh = k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_FALSE(fresh.refactored);
  EXPECT_LE(fresh.iterations, 1);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
}

// The frame a background factorisation is due at follows its cost: ceil(F / flops per frame)
// frames after the request, F the flops of one factorisation (CHOLMOD's analysis, here of the same
// pattern by a factor of its own), 1 to swap_after_frames. Lockstep takes it up exactly there.
TEST(TangentSystem, ABackgroundFactorisationIsDueAsManyFramesAfterItsRequestAsItsFlopsTake) {
  const int n = 200;
  std::vector<int> start, columns;
  tridiagonal_pattern(n, start, columns);
  const double flops = CholeskyFactor(n, start.data(), columns.data()).flops();
  ASSERT_GT(flops, 0);
  for (const auto& [per_frame, due] : std::vector<std::pair<double, int>>{
           {1e9, 1}, {flops / 1.5, 2}, {flops / 2.5, 3}, {flops / 40, 3}, {0.0, 3}}) {
    SCOPED_TRACE(due);
    TangentSystem k;
    k.set_deterministic(true);
    k.background_flops_per_frame = per_frame;
    std::vector<double> b, x;
    drift_by_a_tenth(k, n, b, x, 1e-10);
    ASSERT_TRUE(k.background_under_way());
    EXPECT_EQ(k.background_due_frames(), due);
    for (int frame = 1; frame < due; ++frame) {
      k.begin_frame(true);
      EXPECT_TRUE(k.background_under_way()) << "taken up early, frame " << frame;
    }
    k.begin_frame(true);
    expect_the_requested_k_factorised(k, b, x);
  }
}

// Real time (not deterministic) keeps lockstep's schedule while the worker keeps up: a background
// factorisation that is ready early is still taken up at the third frame, never before, so the
// frames solve what lockstep's solve. One not ready there is not waited for: that frame and each
// after it until it is ready go on with the old factorisation and say so (background_late), and
// it is taken up at the first frame start at which it is.
TEST(TangentSystem, RealTimeTakesTheBackgroundFactorisationUpAtLockstepsFrameOrWhenReady) {
  for (const int n : {200, 400000}) {
    SCOPED_TRACE(n);
    TangentSystem k;
    k.set_deterministic(false);
    k.background_flops_per_frame = 0;  // the schedule of a factorisation that takes frames
    ASSERT_EQ(k.swap_after_frames, 3);
    // CG on the old factorisation converges, in more than refactor_after_iterations and fewer than
    // the frames' limit.
    std::vector<double> b, x;
    const auto [first, drifted] = drift_by_a_tenth(k, n, b, x, 1e-10);
    ASSERT_TRUE(first.refactored);
    ASSERT_FALSE(drifted.refactored);
    ASSERT_GT(drifted.iterations, k.refactor_after_iterations);
    ASSERT_TRUE(k.background_under_way());
    const bool slow = n > 1000;  // factorising 400,000 rows takes milliseconds; a frame start, nanoseconds
    for (int frame = 1; frame < 3; ++frame) {
      if (!slow) std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the 200 rows are factorised by now
      k.begin_frame(true);
      EXPECT_EQ(k.factorisations(), 1) << "taken up before lockstep does, frame " << frame;
      EXPECT_FALSE(k.background_late());
    }
    if (!slow) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      k.begin_frame(true);
      EXPECT_FALSE(k.background_late());
      EXPECT_EQ(k.late_background_frames(), 0);
    } else {
      k.begin_frame(true);
      EXPECT_TRUE(k.background_late());
      EXPECT_TRUE(k.background_under_way());
      EXPECT_EQ(k.factorisations(), 1);
      int late = 1;
      // Until the factorisation is done: under a sanitizer on a busy machine it took over 10 s.
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(2);
      for (int frame = 4; k.background_under_way() && std::chrono::steady_clock::now() < give_up; ++frame) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        k.begin_frame(true);
        EXPECT_EQ(k.background_late(), k.background_under_way()) << frame;
        late += k.background_late();
      }
      EXPECT_EQ(k.late_background_frames(), late);
    }
    expect_the_requested_k_factorised(k, b, x);
  }
}

// The worker's first job is a warm-up factorisation (thrown away) started with the first one. A
// request made while it runs is queued behind it rather than waited for in the frame that made it;
// the factorisation taken up is still that of K as it was at the request (CG against it: one
// iteration), not the warm-up's K, in lockstep (waited for at the third frame) and in real time.
TEST(TangentSystem, ARequestDuringTheWarmUpIsQueuedBehindItAndFactorisesTheRequestedK) {
  for (const bool deterministic : {true, false}) {
    SCOPED_TRACE(deterministic ? "lockstep" : "real time");
    const int n = 200000;  // a warm-up of milliseconds; the request follows the first solve at once
    TangentSystem k;
    k.set_deterministic(deterministic);
    k.background_flops_per_frame = 0;  // the schedule of a factorisation that takes frames
    k.refactor_after_iterations = 0;  // the first CG iteration on a drifted K asks for a new factorisation
    std::vector<double> b, x;
    const auto [first, drifted] = drift_by_a_tenth(k, n, b, x, 1e-2);
    ASSERT_TRUE(first.refactored);
    ASSERT_FALSE(drifted.refactored);
    ASSERT_TRUE(k.background_under_way());
    EXPECT_LE(k.requests_queued_behind_warm_up(), 1);
    if (k.requests_queued_behind_warm_up() == 0) std::printf("the warm-up had ended before the request\n");
    for (int frame = 1; k.background_under_way() && frame < 100000; ++frame) {
      if (frame >= 3) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      k.begin_frame(true);
      if (deterministic) {
        EXPECT_EQ(k.background_under_way(), frame < 3) << frame;
      }
    }
    expect_the_requested_k_factorised(k, b, x);
  }
}

// The blocked product against the closed form: (K x)_i = d x_i - x_{i-1} - x_{i+1} for every
// vector of a block, whatever the block's size (passes of 4, 3, 2 and 1 vectors).
TEST(TangentSystem, BlockedProductMatchesTheStencil) {
  const int n = 37;
  const double d = 2.5;
  TangentSystem k;
  tridiagonal(k, n, d);
  for (const int columns : {1, 2, 3, 4, 6, 9}) {
    std::vector<std::vector<double>> x(columns, std::vector<double>(n)), y(columns, std::vector<double>(n, -1));
    std::vector<const double*> in;
    std::vector<double*> out;
    for (int j = 0; j < columns; ++j) {
      for (int i = 0; i < n; ++i) x[j][i] = std::cos(0.3 * i * (j + 1)) + j;
      in.push_back(x[j].data()), out.push_back(y[j].data());
    }
    k.multiply_columns(in.data(), out.data(), columns);
    for (int j = 0; j < columns; ++j)
      for (int i = 0; i < n; ++i) {
        const double expected = d * x[j][i] - (i > 0 ? x[j][i - 1] : 0) - (i + 1 < n ? x[j][i + 1] : 0);
        EXPECT_NEAR(y[j][i], expected, 1e-13) << columns << " vectors, vector " << j << ", row " << i;
      }
  }
}

TEST(TangentSystem, IndefiniteMatrixFallsBackToLdl) {
  const int n = 50;
  TangentSystem k;
  tridiagonal(k, n, 0.5);  // eigenvalues 0.5 - 2 cos(pi j/51): both signs, the smallest 0.047 in size
  std::vector<double> b(n, 1.0), x(n);
  k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
}

// A singular K that is also indefinite, so that CHOLMOD cannot take it: tridiag(-1, 0.5, -1) on
// 49 unknowns (eigenvalues of both signs) and a 50th unknown with no stiffness at all (a zero row,
// as a dof that nothing holds). It is factorised by MUMPS's LDL' with the null pivot fixed, and a
// right-hand side it can balance (0 on that unknown) is solved: K x = b to the tolerance. Without
// the null-pivot detection (ICNTL(24) = 0) the factorisation fails as singular, as every cut of a
// Newton step at such a state did (docs/solver.md).
TEST(TangentSystem, ASingularKIsFactorisedWithItsNullPivotsFixed) {
  const int n = 50;
  const auto held_by_nothing = [&](TangentSystem& k) {
    tridiagonal(k, n, 0.5);
    k.zero();
    for (int i = 0; i + 1 < n; ++i) {
      k.add(i, i, 0.5);
      if (i > 0) k.add(i, i - 1, -1);
      if (i + 2 < n) k.add(i, i + 1, -1);
    }
    k.finish(std::vector<bool>(n, false));
  };
  std::vector<double> b(n, 0.0), x(n);
  for (int i = 0; i + 1 < n; ++i) b[i] = std::cos(0.3 * i);
  {
    TangentSystem k;
    held_by_nothing(k);
    std::fill(x.begin(), x.end(), 0.0);
    EXPECT_NO_THROW(k.solve(b.data(), x.data(), 1e-10, true));
    EXPECT_FALSE(k.cholmod());
    EXPECT_LT(relative_residual(k, b, x), 1e-10);
  }
  ASSERT_EQ(PetscOptionsSetValue(nullptr, "-mat_mumps_icntl_24", "0"), 0);
  {
    TangentSystem k;
    held_by_nothing(k);
    std::fill(x.begin(), x.end(), 0.0);
    EXPECT_THROW(k.solve(b.data(), x.data(), 1e-10, true), std::runtime_error);
  }
  ASSERT_EQ(PetscOptionsClearValue(nullptr, "-mat_mumps_icntl_24"), 0);
}

// A K that is not positive definite is factorised by LDL' for as long as K stays so, not for the rest
// of the session: outside frames the next factorisation of a positive definite K is CHOLMOD's again.
// tridiag(-1, 0.5, -1) has eigenvalues of both signs, tridiag(-1, 3, -1) lies in 1..5.
TEST(TangentSystem, AnIndefiniteKLeavesCholmodOnlyUntilTheNextPositiveDefiniteOne) {
  const int n = 50;
  TangentSystem k;
  std::vector<double> b(n), x(n);
  for (int i = 0; i < n; ++i) b[i] = std::cos(0.3 * i);
  tridiagonal(k, n, 3.0);
  k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_TRUE(k.cholmod());
  // K with this diagonal, factorised afresh: solved, and on CHOLMOD or not as `positive_definite`.
  const auto refactorise = [&](double diagonal, bool positive_definite) {
    SCOPED_TRACE(diagonal);
    tridiagonal(k, n, diagonal);
    k.refactor_next();
    EXPECT_TRUE(k.solve(b.data(), x.data(), 1e-10, true).refactored);
    EXPECT_LT(relative_residual(k, b, x), 1e-10);
    EXPECT_EQ(k.cholmod(), positive_definite);
    EXPECT_EQ(k.cholmod_departures(), 1);
  };
  refactorise(0.5, false);
  refactorise(3.0, true);
}

// Within frames (lockstep) a factorisation due there finds K not positive definite: LDL' carries
// the frames, and once K is positive definite again and CG on the old factorisation drifts, the
// worker's CHOLMOD factorisation is taken up at its due frame (the next one, for so few flops) and
// the solves are back on CHOLMOD. Every solve meets its tolerance on the way.
TEST(TangentSystem, WithinFramesTheWorkersFactorisationBringsTheSolvesBackToCholmod) {
  const int n = 200;
  TangentSystem k;
  k.set_deterministic(true);
  std::vector<double> b(n), x(n, 0.0);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.1 * i) + 0.5;
  tridiagonal(k, n, 3.0);
  k.begin_frame(true);
  k.solve(b.data(), x.data(), 1e-10, true);
  ASSERT_TRUE(k.cholmod());
  tridiagonal(k, n, 0.5);
  k.refactor_next();
  k.begin_frame(true);
  k.solve(b.data(), x.data(), 1e-10, true);
  EXPECT_LT(relative_residual(k, b, x), 1e-10);
  EXPECT_FALSE(k.cholmod());
  // Positive definite from here, stiffening frame by frame (the old factorisation drifts).
  double diagonal = 2.2;
  int frames = 0;
  for (; frames < 12 && !k.cholmod(); ++frames, diagonal *= 1.15) {
    tridiagonal(k, n, diagonal);
    k.begin_frame(true);
    k.solve(b.data(), x.data(), 1e-10, frames == 0);
    EXPECT_LT(relative_residual(k, b, x), 1e-10) << "frame " << frames;
  }
  EXPECT_TRUE(k.cholmod()) << "still on LDL' after " << frames << " frames";
  EXPECT_GE(k.background_factorisations(), 1);
  EXPECT_EQ(k.cholmod_departures(), 1);
}

// The 7-point Laplacian on an m^3 grid with a coefficient per cell drawn over three decades (a
// soft sac around a stiff head has such contrasts), Dirichlet outside: SPD and poorly conditioned.
// `drift` scales the coefficients by 1 + drift * (a smooth field), as a later state's tangent.
void variable_laplacian(TangentSystem& k, int m, double drift) {
  const int n = m * m * m;
  const auto at = [m](int x, int y, int z) { return (z * m + y) * m + x; };
  const auto coefficient = [&](int x, int y, int z) {  // deterministic, 1e-1.5 .. 1e1.5
    const double u = std::sin(12.9898 * x + 78.233 * y + 37.719 * z) * 43758.5453;
    return std::pow(10.0, 3 * (u - std::floor(u)) - 1.5) * (1 + drift * std::cos(0.3 * x + 0.2 * z));
  };
  std::vector<int> start{0}, columns;
  for (int z = 0; z < m; ++z)
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        std::vector<int> row{at(x, y, z)};
        if (x > 0) row.push_back(at(x - 1, y, z));
        if (x + 1 < m) row.push_back(at(x + 1, y, z));
        if (y > 0) row.push_back(at(x, y - 1, z));
        if (y + 1 < m) row.push_back(at(x, y + 1, z));
        if (z > 0) row.push_back(at(x, y, z - 1));
        if (z + 1 < m) row.push_back(at(x, y, z + 1));
        std::sort(row.begin(), row.end());
        columns.insert(columns.end(), row.begin(), row.end());
        start.push_back(static_cast<int>(columns.size()));
      }
  if (k.rows() != static_cast<std::size_t>(n))
    k.set_pattern(start, columns, TangentSystem::Method::factorisation, 0, n);
  k.zero();
  for (int z = 0; z < m; ++z)
    for (int y = 0; y < m; ++y)
      for (int x = 0; x < m; ++x) {
        const int i = at(x, y, z);
        const double c = coefficient(x, y, z);
        const int neighbours[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z},
                                      {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
        for (const auto& q : neighbours) {
          const bool inside = q[0] >= 0 && q[0] < m && q[1] >= 0 && q[1] < m && q[2] >= 0 && q[2] < m;
          const double edge = inside ? std::sqrt(c * coefficient(q[0], q[1], q[2])) : c;
          k.add(i, i, edge);
          if (inside) k.add(i, at(q[0], q[1], q[2]), -edge);
        }
      }
  k.finish(std::vector<bool>(n, false));
}

// CG on a stale factorisation applies its single-precision copy to the tolerances a frame asks
// for, in about the iterations the double factor takes; tighter solves and a just-made
// factorisation (the solution itself) apply the double factor, to double accuracy. The copy is the
// same factor: its answers are the double one's to single precision, column by column or in blocks.
TEST(TangentSystem, ASinglePrecisionCopyPreconditionsFramesAndTightSolvesStayDouble) {
  const int m = 14, n = m * m * m;
  std::vector<double> b(n);
  for (int i = 0; i < n; ++i) b[i] = std::cos(0.37 * i) + 0.5;
  std::vector<double> reference(3 * n);
  int loose[2] = {0, 0}, tight[2] = {0, 0};
  for (const bool single : {false, true}) {
    SCOPED_TRACE(single ? "single" : "double");
    TangentSystem k;
    k.single_precision_preconditioner = single;
    k.single_precision_min_entries = 0;  // this factor is small
    variable_laplacian(k, m, 0.0);
    std::vector<double> x(n);
    const TangentSystem::SolveStats first = k.solve(b.data(), x.data(), 1e-12, true);
    EXPECT_TRUE(first.refactored);
    EXPECT_EQ(k.keeps_single_precision(), single);
    EXPECT_LT(relative_residual(k, b, x), 1e-12) << "a fresh factorisation is applied in double";
    // The factor applied to three columns in a block and one at a time.
    std::vector<double> block(3 * n), together(3 * n), alone(3 * n);
    for (int i = 0; i < 3 * n; ++i) block[i] = std::sin(0.11 * i);
    k.apply_factorisation(block.data(), together.data(), 3);
    for (int c = 0; c < 3; ++c) k.apply_factorisation(block.data() + c * n, alone.data() + c * n, 1);
    double blocks = 0, size = 0;
    for (int i = 0; i < 3 * n; ++i)
      blocks = std::max(blocks, std::abs(together[i] - alone[i])), size = std::max(size, std::abs(alone[i]));
    EXPECT_LT(blocks, 1e-5 * size);
    if (!single) reference = alone;
    double from_double = 0;
    for (int i = 0; i < 3 * n; ++i) from_double = std::max(from_double, std::abs(alone[i] - reference[i]));
    EXPECT_LT(from_double, 1e-4 * size);
    if (single) {
      EXPECT_GT(from_double, 0.0) << "the copy was not used";
    }
    // 2 % drift: CG on the old factorisation, to a frame's tolerance and to a static solve's.
    variable_laplacian(k, m, 0.02);
    for (const double tolerance : {1e-4, 1e-12}) {
      std::fill(x.begin(), x.end(), 0.0);
      const TangentSystem::SolveStats drifted = k.solve(b.data(), x.data(), tolerance, true);
      EXPECT_FALSE(drifted.refactored);
      EXPECT_LT(relative_residual(k, b, x), tolerance);
      (tolerance > 1e-6 ? loose : tight)[single] = drifted.iterations;
    }
  }
  std::printf("CG iterations after 2 %% drift, double factor / single copy: %d / %d to 1e-4, %d / %d to 1e-12\n",
              loose[0], loose[1], tight[0], tight[1]);
  EXPECT_LE(loose[1], loose[0] + 1);
  EXPECT_EQ(tight[1], tight[0]);
}

}  // namespace
}  // namespace fetouch::fem

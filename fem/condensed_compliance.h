// The condensed compliance at the contacts: W = H K^-1 H' (3m x 3m, m/N; row/column 3a + c is
// patch a, component c), K the current tangent with the supports. Its columns Z = K^-1 H' are kept:
// the next W starts from them (a Galerkin update in their span, no solve, when the state moved
// little), and a frame that changes only the patch forces predicts its solution as u + Z dF.
#pragma once

#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>

#include <utility>
#include <vector>

#include "fem/linear_system.h"

namespace fetouch::fem {

struct ComplianceTimes {
  double assembly_s = 0, factorisation_s = 0, solves_s = 0;
  double total_s = 0;  // the whole update: the phases, the products with K and the Galerkin algebra
  int linear_iterations = 0, factorisations = 0;
  double galerkin_residual = 0;  // of the last columns' Galerkin update (0: none)
  double first_residual = 0;     // of the old columns' Galerkin update alone, before any direction joined
  bool refined = false;          // the columns were solved again
  int recycled_directions = 0;   // directions of the update before that joined the span
  int rounds = 0;                // applications of the factorisation to the residuals of the columns that missed
  int new_directions = 0;        // directions those rounds added (one for each column that missed)
  int products = 0;              // vectors multiplied by K (the basis's, for the Galerkin projection)
  double products_s = 0;         // their time; the rest of total_s beside the phases is dense algebra
  bool carrier_kept = false;     // the liquid's carrier was the one kept from an earlier update
};

// The relative residual to which compliance columns K^-1 h are solved.
inline constexpr double kComplianceTolerance = 1e-9;
// The largest relative residual of a Galerkin-updated column accepted without a new solve, by
// default: the error of W is then of the order of its square, 1e-6 relative. A scene's accuracy
// policy may accept more (CondensedCompliance::galerkin_tolerance).
inline constexpr double kGalerkinTolerance = 1e-3;
// Rounds of enlarging the span by preconditioned residuals before the columns are solved afresh.
inline constexpr int kMaxGalerkinRounds = 6;
// Directions of the last update's rounds kept for the next one, per column of W.
inline constexpr std::size_t kRecycledPerColumn = 4;

class CondensedCompliance {
 public:
  // W for the rows h (3m of them, constrained entries zero) with the system's current tangent;
  // fills `times` (but assembly_s) from the system's accumulated times.
  dealii::FullMatrix<double> compute(LinearSystem& system, const std::vector<dealii::Vector<double>>& h,
                                     ComplianceTimes& times);
  // Z = K^-1 H' of the last W (empty before the first, or after clear()).
  const std::vector<dealii::Vector<double>>& columns() const { return z_; }
  void clear() { z_.clear(), recycled_.reset(0), recycled_column_.clear(), carrier_.reinit(0); }
  double galerkin_tolerance = kGalerkinTolerance;

 private:
  // Vectors of one length side by side, column-major (n x count), so that the Galerkin algebra on
  // them (B'K B, H B, B C) is matrix products; the storage is kept from one update to the next.
  class Columns {
   public:
    void reset(std::size_t n) { n_ = n, count_ = 0; }
    std::size_t count() const { return count_; }
    std::size_t length() const { return n_; }
    double* operator[](std::size_t j) { return data_.data() + j * n_; }
    const double* operator[](std::size_t j) const { return data_.data() + j * n_; }
    double* add();  // a new last column (its entries unset)
    void resize(std::size_t count);
    void swap(Columns& other) { data_.swap(other.data_), std::swap(n_, other.n_), std::swap(count_, other.count_); }

   private:
    std::vector<double> data_;
    std::size_t n_ = 0, count_ = 0;
  };

  std::vector<dealii::Vector<double>> z_;
  Columns recycled_;  // the last rounds' directions, newest first
  std::vector<unsigned int> recycled_column_, kept_column_;  // the column of W each direction came from
  Columns basis_, kb_, h_, z_block_, kz_block_, kept_;  // the update's working storage
  dealii::Vector<double> scratch_;
  dealii::Vector<double> carrier_;  // (P + c g g')^-1 g of the liquid's g, at some earlier state
  double carrier_cosine_ = 0;       // its cosine with g when it was computed
};

}  // namespace fetouch::fem

// Hyperelasticity in total Lagrangian form, always part of a body:
//   f_int = int_Omega P(F) : grad v dV,    K = int grad v : A(F) : grad du dV,   F = I + grad u,
// with a material per region (cells by material id; the body's material elsewhere).
//
// Mean dilatation (Simo, Taylor and Pister), for nearly incompressible decoupled materials: the
// volumetric energy U(J) is taken of each cell's volume ratio theta = (1/V) int J dV instead of J
// pointwise, i.e. a displacement-pressure formulation with the pressure constant per cell,
// condensed (Q1/P0, P2/P0). P1 tetrahedra have one point: no change.
//
// Two threads (the machine has 2 cores; the haptic thread sleeps between its microsecond ticks)
// assemble the two halves of this rank's cells on either side of a plane, each straight into the
// shared residual and tangent: a cell is given to a thread only if none of its dofs is touched by
// the other half, so no two threads ever write the same row; the cells along the cut (a layer, a
// few percent of them) follow on one thread. One thread (set_threads(1), or while a background
// factorisation holds the other core) takes the two halves in turn and then the cut: each row's sum
// is over the same cells in the same order either way, so the result is the same to the bit on one
// thread or two, and reproducible run to run.
#pragma once

#include <array>
#include <map>
#include <vector>

#include "fem/discretisation.h"
#include "fem/material.h"
#include "fem/pair_worker.h"
#include "fem/term.h"

namespace fetouch::fem {

class ElasticityTerm final : public Term {
 public:
  ElasticityTerm(const Discretisation& discretisation, const Material& body);
  const char* name() const override { return "elasticity"; }
  bool distributed() const override { return true; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;

  // Cells with this material id take `material` (kept by reference).
  void set_region_material(unsigned int material_id, const Material& material);
  // Throws std::invalid_argument for a coupled material (no volumetric part to take per cell).
  void use_mean_dilatation(bool on);
  const Material& material_of(unsigned int cell) const;

  // 1 or 2 (the default) threads over this rank's cells; one in parallel runs (the ranks take the
  // cores) and below 2 kCellsPerThread cells.
  void set_threads(unsigned int threads) { threads_ = threads; }
  static constexpr unsigned int kCellsPerThread = 1000;

 private:
  bool assemble_cells(const std::vector<unsigned int>& cells, const dealii::Vector<double>& u, double* r,
                      double* internal, double* values, const LinearSystem& system) const;
  template <int NB>
  bool assemble_fixed(const std::vector<unsigned int>& cells, const dealii::Vector<double>& u, double* r,
                      double* internal, double* values, const LinearSystem& system) const;
  void plan_threads() const;
  const Discretisation& d_;
  const Material& body_;
  std::map<unsigned int, const Material*> regions_;
  mutable std::vector<const Material*> cell_material_;  // per cell, built on first use
  bool mean_dilatation_ = false;
  unsigned int threads_ = 2;
  // The first thread's cells and the second's, then, after both, the cells along their cut split
  // the same way (the first thread's, the second's), then the cells along that second cut; the first
  // holds every cell below 2 kCellsPerThread cells and in parallel runs. Built on first use.
  mutable std::array<std::vector<unsigned int>, 5> plan_;
  mutable bool planned_ = false;
  // The assembling thread may run on more than 2 cores: a second thread need not share the
  // background factoriser's. Read with the plan.
  mutable bool spare_core_ = false;
  PairWorker worker_;  // the second thread of each pair of groups
};

// Throws std::invalid_argument naming the material if it is not decoupled.
void require_decoupled(const Material& material);

}  // namespace fetouch::fem

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
// assemble halves of this rank's cells, the second into its own buffers, added afterwards.
#pragma once

#include <map>
#include <vector>

#include "fem/discretisation.h"
#include "fem/material.h"
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

  static constexpr unsigned int kCellsPerThread = 1000;  // fewer: one thread

 private:
  bool assemble_cells(unsigned int begin, unsigned int end, const dealii::Vector<double>& u, double* r,
                      double* internal, double* values, const LinearSystem& system) const;
  const Discretisation& d_;
  const Material& body_;
  std::map<unsigned int, const Material*> regions_;
  mutable std::vector<const Material*> cell_material_;  // per cell, built on first use
  bool mean_dilatation_ = false;
  struct Buffers {
    std::vector<double> r, internal, values;
  } second_;
};

// Throws std::invalid_argument naming the material if it is not decoupled.
void require_decoupled(const Material& material);

}  // namespace fetouch::fem

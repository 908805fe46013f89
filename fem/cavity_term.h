// The fluid-filled cavity (cavity.h) as a term: the pressure p is an unknown beside u, with the
// law's residual V(u) - V_law(p) = 0. The wall carries the load p g (g = dV/du), the sparse tangent
// gains -p d2V/du2, and eliminating dp adds (-dp/dV) g g' (dense, rank one: the linear system
// applies it by Sherman-Morrison). Taking p = p(V(u)) instead, a liquid's stiffness K/V0 ~ 1e13 Pa/m^3
// turns any second-order volume error of a step into a huge force: Newton stalls.
// The pressure is part of the body's response: it is not scaled by load steps.
#pragma once

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "fem/cavity.h"
#include "fem/discretisation.h"
#include "fem/term.h"

namespace fetouch::fem {

class CavityTerm final : public Term {
 public:
  // Throws std::invalid_argument for a surface that encloses no volume. Elements of degree 1 or 2
  // (the wall's faces flat, or curved through their nodes: cavity.h).
  CavityTerm(const Discretisation& discretisation, unsigned int boundary_id, const CavityLaw& law);
  // The cavity as the cells of the material ids `contents` (a fluid region, and what floats in it):
  // its wall is their boundary against the other cells and the outside, so that the law holds for
  // their total volume and the pressure acts on the wall around them. Throws std::invalid_argument
  // when no cell is in `contents` or every cell is.
  CavityTerm(const Discretisation& discretisation, const std::set<unsigned int>& contents, const CavityLaw& law);
  const char* name() const override { return "cavity"; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;
  bool rank_one(double& c, const dealii::Vector<double>*& g) const override;
  double rank_one_load() const override;
  void complete_step(const LinearSystem& system, dealii::Vector<double>& du) override;
  void take_step(double alpha) override { pressure_ = step_start_ + alpha * dp_; }
  bool restore(dealii::Vector<double>& u, LinearSystem& system, double negligible_force) override;
  double unknown() const override { return pressure_; }
  void set_unknown(double value) override { pressure_ = value; }
  bool satisfied() const override { return std::abs(volume_residual_) <= 1e-10 * reference_volume_; }
  // The law p(V) has an energy (-integral of p dV), and every trial state of the line search is
  // restored onto the law to first order (restore()): there the wall's load p g is the gradient of
  // the reduced energy W(u) - f.u + Phi(V(u)), so the line search may follow its slope. (Halving on
  // the residual's norm instead stalled: near-inverted soft cells make a good step's residual grow
  // as alpha^2, and steps of 1/16 took 1 % off it per iteration.)
  bool conservative() const override { return true; }

  double volume(const dealii::Vector<double>& u) const { return wall_.volume(u.begin()); }
  double reference_volume() const { return reference_volume_; }
  double pressure() const { return pressure_; }

 private:
  void finish_setup(const Discretisation& discretisation, const std::string& what);

  CavityLaw law_;
  CavityWall wall_;
  double reference_volume_ = 0, stiffness_ = 0;
  double pressure_ = 0, step_start_ = 0, dp_ = 0;
  double volume_residual_ = 0;  // V(u) - V_law(p), m^3, at the last assembly
  dealii::Vector<double> g_;
  dealii::Vector<double> w_;  // restore()'s direction
  std::vector<int> positions_;  // each Hessian entry's place in the tangent's values (-1: constrained)
  int positions_revision_ = -1;  // the pattern they were found in
};

}  // namespace fetouch::fem

// A term of the weak form: one effect's contribution to the residual r(u) = f_ext - f_int and to
// the tangent K = -dr/du. The Newton driver (newton_driver.h) iterates over whatever terms it is
// given and knows none of them by name; a scene that does not list an effect never builds its term.
//
// Terms are assembled in the order given. `distributed` terms loop over this rank's cells and are
// summed over the MPI ranks afterwards; the others are evaluated whole on every rank, after that sum.
// A term may carry state beyond u (a time step's start, a cavity's pressure): begin_solve() sees the
// state a solve starts from, accept() the converged one; a scalar unknown of its own is saved and
// rolled back with u (unknown()/set_unknown()). A term with a scalar unknown of its own completes each Newton step for it.
#pragma once

#include <deal.II/lac/vector.h>

#include <vector>

namespace fetouch::fem {

class LinearSystem;

// The state at which a term is assembled.
struct AssemblyState {
  const dealii::Vector<double>& u;
  double static_factor;  // supports, tractions, body force: the fraction of their full value
  double patch_lambda;   // patch forces: 0 the last converged value, 1 the new one
};

// Where a term's contributions go.
struct AssemblyTarget {
  double* residual;            // += f_ext - f_int on free dofs (the driver zeroes constrained ones)
  double* internal = nullptr;  // += f_int - f_ext of the body itself on every dof (reactions), or null
  double* tangent = nullptr;   // the tangent's value array, or null when only r is wanted
  const LinearSystem* system;  // the tangent's pattern and the constrained dofs
};

class Term {
 public:
  virtual ~Term() = default;
  virtual const char* name() const = 0;
  virtual bool distributed() const { return false; }
  // Adds the term's part; false when the state is inadmissible (an element inverted, a cavity
  // collapsed): the driver then rejects the state.
  virtual bool assemble(const AssemblyState& state, AssemblyTarget& target) = 0;

  virtual void begin_solve(const dealii::Vector<double>& /*u*/) {}
  virtual void accept(const dealii::Vector<double>& /*u*/) {}
  // A scalar unknown of the term's own beside u (a cavity's pressure): rolled back with u.
  virtual double unknown() const { return 0; }
  virtual void set_unknown(double /*value*/) {}

  // A dense rank-one tangent part c g g' beside the sparse one (after a tangent assembly), applied
  // by the linear system through the Sherman-Morrison formula.
  virtual bool rank_one(double& /*c*/, const dealii::Vector<double>*& /*g*/) const { return false; }
  // The term's own equation, eliminated into the step: the right-hand side of K du = r gets this
  // multiple of g (after an assembly).
  virtual double rank_one_load() const { return 0; }
  // Complete the Newton step du for the term's unknown (du solves K du = r + rank_one_load() g with
  // K including the rank-one part); take_step(alpha) then moves the unknown by alpha times its step
  // from where it was when the step was completed.
  virtual void complete_step(const LinearSystem& /*system*/, dealii::Vector<double>& /*du*/) {}
  virtual void take_step(double /*alpha*/) {}
  // u was moved by a linear prediction (a frame's first guess): restore the term's own equation to
  // first order by moving u and the unknown along a direction that keeps the force balance to first
  // order (given by the factorisation of a recent tangent, `system`), unless the nodal force the
  // restoration would move is at most `negligible_force` (N; 0: only when there is nothing to do).
  // Returns whether u moved.
  virtual bool restore(dealii::Vector<double>& /*u*/, LinearSystem& /*system*/, double /*negligible_force*/) {
    return false;
  }
  // The term's own equation holds (a cavity's volume law), beside the residual's norm.
  virtual bool satisfied() const { return true; }
  // The term's residual is minus the gradient of an energy of u alone (hyperelasticity, dead loads,
  // an implicit time step's incremental potential): the line search may then follow that energy.
  virtual bool conservative() const { return true; }
};

}  // namespace fetouch::fem

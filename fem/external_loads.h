// Dead loads: tractions (force per reference area, N/m^2) on boundary regions and a body force per
// reference volume (N/m^3, gravity), as one load vector f_ext = int_Gamma t . v dA + int_Omega b . v dV
// built once (total Lagrangian: it does not depend on u) and scaled by the static load factor.
#pragma once

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <functional>
#include <vector>

#include "fem/discretisation.h"
#include "fem/term.h"

namespace fetouch::fem {

class ExternalLoadsTerm final : public Term {
 public:
  explicit ExternalLoadsTerm(const Discretisation& discretisation) : d_(discretisation) {}
  const char* name() const override { return "loads"; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;

  void add_traction(unsigned int boundary_id, const dealii::Tensor<1, 3>& traction);
  // Per reference volume, at a point of a cell with this material id.
  using BodyForce = std::function<dealii::Tensor<1, 3>(const dealii::Point<3>&, unsigned int material_id)>;
  void set_body_force(BodyForce force);

 private:
  void build();
  const Discretisation& d_;
  struct Traction {
    unsigned int boundary;
    dealii::Tensor<1, 3> value;
  };
  std::vector<Traction> tractions_;
  BodyForce body_force_;
  dealii::Vector<double> external_;  // at full load
  bool built_ = false;
};

}  // namespace fetouch::fem

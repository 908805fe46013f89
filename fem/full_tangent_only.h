// A material seen through evaluate() only: the assembly then contracts the full 81-entry tangent
// instead of the split one (SplitTangent). For the tests that compare the two kernels and the
// benchmark that times them; the solver never uses it.
#pragma once

#include <string>

#include "fem/material.h"

namespace fetouch::fem {

class FullTangentOnly final : public Material {
 public:
  explicit FullTangentOnly(const Material& m) : m_(m) {}
  std::string name() const override { return m_.name(); }
  double energy(const Tensor2& F) const override { return m_.energy(F); }
  bool evaluate(const Tensor2& F, Tensor2& P, Tensor4* A) const override { return m_.evaluate(F, P, A); }
  double shear_modulus() const override { return m_.shear_modulus(); }
  double bulk_modulus() const override { return m_.bulk_modulus(); }
  bool volumetric(double j, double& u1, double& u2) const override { return m_.volumetric(j, u1, u2); }

 private:
  const Material& m_;  // outlives this
};

}  // namespace fetouch::fem

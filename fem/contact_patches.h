// Contact patches (ARCHITECTURE.md section 4): a probe acts on the surface through a smooth kernel
// w(X) = (1 - (d/r)^2)^2 for reference distances d < r from the patch centre, normalised to unit
// integral over the boundary. H_a u = int w_a u dA is the patch's displacement; a patch force F_a is
// the traction w_a F_a, i.e. the load vector H_a' F_a, moved by the load factor from the force of the
// last converged solve to the new one. The deformed normal there is the kernel-weighted average of
// the deformed face normals (Nanson: n da = J F^-T N dA).
#pragma once

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/fe/fe_update_flags.h>

#include <array>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "fem/discretisation.h"
#include "fem/term.h"

namespace dealii {
template <int dim, int spacedim>
class FEFaceValues;
}

namespace fetouch::fem {

class ContactPatchesTerm final : public Term {
 public:
  explicit ContactPatchesTerm(const Discretisation& discretisation);
  ~ContactPatchesTerm() override;
  const char* name() const override { return "contact"; }
  bool assemble(const AssemblyState& state, AssemblyTarget& target) override;
  void accept(const dealii::Vector<double>& u) override;

  struct Patch {
    dealii::Point<3> center;
    double radius = 0;
    std::array<dealii::Vector<double>, 3> h;  // H rows, one per component
    dealii::Tensor<1, 3> force;
    dealii::Tensor<1, 3> converged_force;     // the force of the last converged solve
  };
  // Throws std::invalid_argument with no boundary within the radius (nothing changed then).
  int add(const dealii::Point<3>& center, double radius);
  void move(int patch, const dealii::Point<3>& center);
  void set_force(int patch, const dealii::Tensor<1, 3>& force) { patches_.at(patch).force = force; }
  const Patch& operator[](int patch) const { return patches_.at(patch); }
  int size() const { return static_cast<int>(patches_.size()); }
  bool forces_changed() const;

  dealii::Tensor<1, 3> displacement(int patch, const dealii::Vector<double>& u) const;
  dealii::Tensor<1, 3> deformed_normal(int patch, const dealii::Vector<double>& u) const;

 private:
  void build(Patch& p) const;
  dealii::FEFaceValues<3, 3>& face_values(unsigned int subdivisions, dealii::UpdateFlags flags) const;
  template <class Visit>
  void for_each_patch_point(const Patch& p, dealii::UpdateFlags flags, Visit visit) const;

  const Discretisation& d_;
  std::vector<Patch> patches_;
  mutable std::map<std::pair<unsigned int, unsigned int>, std::unique_ptr<dealii::FEFaceValues<3, 3>>> face_values_;
};

}  // namespace fetouch::fem

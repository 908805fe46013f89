// The elasticity term's assembled tangent against central finite differences of its own assembled
// residual at a large deformation (P1, P2, Q1 with mean dilatation), and the split kernel (the
// neo-Hookean models' tangent contracted from five scalars and F^-T) against the kernel that
// contracts the full 81-entry tangent: the same matrix to round-off.
#include <gtest/gtest.h>

#include <deal.II/dofs/dof_tools.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "fem/discretisation.h"
#include "fem/elasticity_term.h"
#include "fem/full_tangent_only.h"
#include "fem/linear_system.h"
#include "fem/material.h"

namespace fetouch::fem {
namespace {

constexpr double kSide = 0.05;  // m

struct Assembled {
  std::vector<double> residual, tangent;
};

class Assembly {
 public:
  Assembly(const dealii::Triangulation<3>& tria, int degree) : d_(tria, degree, MPI_COMM_SELF), system_(d_, MPI_COMM_SELF) {
    system_.set_up({}, TangentSystem::Method::factorisation);  // no supports: every dof free
  }
  unsigned int n() const { return d_.n_dofs(); }

  // A large, non-uniform deformation: a stretch, a shear and a twist-like term, J well above 0.
  dealii::Vector<double> deformation() const {
    std::vector<dealii::Point<3>> points(n());
    dealii::DoFTools::map_dofs_to_support_points(*d_.mapping, d_.dof, points);
    const std::vector<int> component = d_.dof_components();
    dealii::Vector<double> u(n());
    for (unsigned int i = 0; i < n(); ++i) {
      const dealii::Point<3>& x = points[i];
      const double s = x[2] / kSide;
      const double shift[3] = {0.25 * x[0] + 0.2 * x[2] * s, -0.15 * x[1] + 0.1 * x[0] * s, 0.3 * x[2] - 0.1 * x[1] * s};
      u[i] = shift[component[i]];
    }
    return u;
  }

  Assembled assemble(const Material& material, bool mean_dilatation, const dealii::Vector<double>& u, bool tangent) {
    ElasticityTerm term(d_, material);
    term.use_mean_dilatation(mean_dilatation);
    Assembled a;
    a.residual.assign(n(), 0.0);
    TangentSystem& k = system_.tangent();
    if (tangent) std::fill(k.values(), k.values() + k.nonzeros(), 0.0);
    AssemblyState state{u, 1.0, 1.0};
    AssemblyTarget target{a.residual.data(), nullptr, tangent ? k.values() : nullptr, &system_};
    EXPECT_TRUE(term.assemble(state, target));
    if (tangent) a.tangent.assign(k.values(), k.values() + k.nonzeros());
    return a;
  }

  // K v with the assembled values.
  std::vector<double> product(const std::vector<double>& values, const std::vector<double>& v) const {
    std::vector<double> y(n());
    system_.tangent().multiply(values.data(), v.data(), y.data());
    return y;
  }

 private:
  Discretisation d_;
  LinearSystem system_;
};

double norm(const std::vector<double>& x) {
  double s = 0;
  for (const double v : x) s += v * v;
  return std::sqrt(s);
}

// K v against -(r(u + h v) - r(u - h v)) / 2h for three random directions; and the split kernel's
// values against the full-tangent kernel's.
void check(const dealii::Triangulation<3>& tria, int degree, const Material& material, bool mean_dilatation,
           const char* what) {
  ASSERT_TRUE(material.has_split_tangent()) << what;
  Assembly assembly(tria, degree);
  const dealii::Vector<double> u = assembly.deformation();
  const Assembled split = assembly.assemble(material, mean_dilatation, u, true);
  const Assembled full = assembly.assemble(FullTangentOnly(material), mean_dilatation, u, true);
  double largest = 0, difference = 0;
  for (std::size_t i = 0; i < split.tangent.size(); ++i) {
    largest = std::max(largest, std::abs(full.tangent[i]));
    difference = std::max(difference, std::abs(split.tangent[i] - full.tangent[i]));
  }
  double residual_difference = 0;
  for (std::size_t i = 0; i < split.residual.size(); ++i)
    residual_difference = std::max(residual_difference, std::abs(split.residual[i] - full.residual[i]));
  std::printf("%s, %u dofs: largest |K_split - K_full| / max |K| = %.1e\n", what, assembly.n(), difference / largest);
  EXPECT_LT(difference, 1e-12 * largest) << what;
  EXPECT_LT(residual_difference, 1e-12 * norm(full.residual)) << what;

  std::mt19937 rng(21);
  std::uniform_real_distribution<double> uniform(-1, 1);
  const double h = 1e-7 * kSide;  // the perturbation's largest entry, m
  double worst = 0;
  for (int t = 0; t < 3; ++t) {
    std::vector<double> v(assembly.n());
    for (double& x : v) x = uniform(rng);
    dealii::Vector<double> plus = u, minus = u;
    for (unsigned int i = 0; i < assembly.n(); ++i) plus[i] += h * v[i], minus[i] -= h * v[i];
    const std::vector<double> r_plus = assembly.assemble(material, mean_dilatation, plus, false).residual;
    const std::vector<double> r_minus = assembly.assemble(material, mean_dilatation, minus, false).residual;
    const std::vector<double> kv = assembly.product(split.tangent, v);
    std::vector<double> error(assembly.n());
    for (unsigned int i = 0; i < assembly.n(); ++i) error[i] = kv[i] + (r_plus[i] - r_minus[i]) / (2 * h);
    worst = std::max(worst, norm(error) / norm(kv));
  }
  std::printf("%s: largest |K v - finite difference| / |K v| = %.1e\n", what, worst);
  EXPECT_LT(worst, 1e-6) << what;
}

TEST(Assembly, SplitTangentIsTheResidualsDerivativeP1) {
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_cube_with_simplices(tria, 3, 0, kSide);
  check(tria, 1, NeoHookean(lame_lambda(5000, 0.45), lame_mu(5000, 0.45)), false, "P1 neo-Hookean");
  check(tria, 1, LinearElastic(lame_lambda(5000, 0.3), lame_mu(5000, 0.3)), false, "P1 linear elastic");
}

TEST(Assembly, SplitTangentIsTheResidualsDerivativeP2) {
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_cube_with_simplices(tria, 2, 0, kSide);
  const double e = 5000, nu = 0.49;
  const NearlyIncompressibleNeoHookean material(e / (3 * (1 - 2 * nu)), lame_mu(e, nu));
  check(tria, 2, material, false, "P2 nearly incompressible neo-Hookean");
  check(tria, 2, material, true, "P2 nearly incompressible neo-Hookean, mean dilatation");
}

TEST(Assembly, SplitTangentIsTheResidualsDerivativeQ1MeanDilatation) {
  dealii::Triangulation<3> tria;
  dealii::GridGenerator::subdivided_hyper_cube(tria, 3, 0, kSide);
  const double e = 5000, nu = 0.4999;
  check(tria, 1, NearlyIncompressibleNeoHookean(e / (3 * (1 - 2 * nu)), lame_mu(e, nu)), true,
        "Q1 nearly incompressible neo-Hookean, mean dilatation");
}

}  // namespace
}  // namespace fetouch::fem

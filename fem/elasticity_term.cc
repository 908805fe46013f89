#include "fem/elasticity_term.h"

#include <sched.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>

#include "fem/linear_system.h"

namespace fetouch::fem {

using namespace dealii;

void require_decoupled(const Material& material) {
  double u1 = 0, u2 = 0;
  if (!material.volumetric(1.0, u1, u2))
    throw std::invalid_argument("the mean-dilatation formulation needs a decoupled material (neo_hookean_incompressible "
                                "or mooney_rivlin), not " + material.name());
}

ElasticityTerm::ElasticityTerm(const Discretisation& discretisation, const Material& body)
    : d_(discretisation), body_(body) {}

void ElasticityTerm::set_region_material(unsigned int material_id, const Material& material) {
  if (mean_dilatation_) require_decoupled(material);
  regions_[material_id] = &material;
  cell_material_.clear();
}

void ElasticityTerm::use_mean_dilatation(bool on) {
  if (on) {
    require_decoupled(body_);
    for (const auto& [id, material] : regions_) require_decoupled(*material);
  }
  mean_dilatation_ = on;
}

const Material& ElasticityTerm::material_of(unsigned int cell) const {
  if (cell_material_.empty()) {
    const Discretisation::Cells& c = d_.cells();
    cell_material_.assign(d_.n_cells(), &body_);
    for (unsigned int k = 0; k < d_.n_cells(); ++k) {
      const auto region = regions_.find(c.material_id[k]);
      if (region != regions_.end()) cell_material_[k] = region->second;
    }
  }
  return *cell_material_[cell];
}

namespace {
// FETOUCH_TANGENT=full: every model's tangent contracted in full, as before the split (to measure).
bool full_tangent_requested() {
  static const bool full = [] {
    const char* requested = std::getenv("FETOUCH_TANGENT");
    return requested && std::string(requested) == "full";
  }();
  return full;
}

// The blocks a <= b of a point's tangent from the split form (see SplitTangent), f_a = F grad N_a,
// h_a = H grad N_a:  K_(a,i)(b,k) += jxw [alpha d_ik grad N_a . grad N_b + zeta f_ai f_bk
// + beta h_ai h_bk + gamma h_ak h_bi + eta (f_ai h_bk + h_ai f_bk)]: three multiply-adds an entry,
// and no 81-entry A to build or contract (one assembly 11-20 % faster, docs/benchmarks.md).
template <int NB>
void add_split_tangent(const Tensor<1, 3>* grad, double jxw, const Tensor2& F, const SplitTangent& S, double* cell_matrix) {
  constexpr int N = 3 * NB;
  double f[NB][3], h[NB][3];
  for (int a = 0; a < NB; ++a)
    for (int i = 0; i < 3; ++i) {
      f[a][i] = F[i][0] * grad[a][0] + F[i][1] * grad[a][1] + F[i][2] * grad[a][2];
      h[a][i] = S.H[i][0] * grad[a][0] + S.H[i][1] * grad[a][1] + S.H[i][2] * grad[a][2];
    }
  const double alpha = jxw * S.alpha, zeta = jxw * S.zeta, beta = jxw * S.beta, gamma = jxw * S.gamma,
               eta = jxw * S.eta;
  for (int a = 0; a < NB; ++a) {
    double with_f[3], with_h[3], crossed[3];  // the row's factors of f_b,k, h_b,k and h_b,i
    for (int i = 0; i < 3; ++i) {
      with_f[i] = zeta * f[a][i] + eta * h[a][i];
      with_h[i] = beta * h[a][i] + eta * f[a][i];
      crossed[i] = gamma * h[a][i];
    }
    double diagonal[NB];  // alpha grad_a . grad_b, the same on the three rows of the block
    for (int b = a; b < NB; ++b)
      diagonal[b] = alpha * (grad[a][0] * grad[b][0] + grad[a][1] * grad[b][1] + grad[a][2] * grad[b][2]);
    for (int i = 0; i < 3; ++i) {
      double* row = cell_matrix + std::size_t(3 * a + i) * N;
      for (int b = a; b < NB; ++b) {
        const double* fb = f[b];
        const double* hb = h[b];
        double* x = row + 3 * b;
        for (int k = 0; k < 3; ++k) x[k] += with_f[i] * fb[k] + with_h[i] * hb[k] + crossed[k] * hb[i];
        x[i] += diagonal[b];
      }
    }
  }
}
}  // namespace

// The cells add -f_int into r (free dofs), f_int into `internal` (if given) and, if
// `values`, the tangent into that value array. False if J <= 0 somewhere. NB scalar base functions
// per cell (P1 4, Q1 8, P2 10, Q2 27): every per-cell array has a fixed size, and the tangent, symmetric
// for a hyperelastic material, is computed on and above its diagonal and mirrored.
template <int NB>
bool ElasticityTerm::assemble_fixed(const std::vector<unsigned int>& cells, const Vector<double>& u, double* r,
                                    double* internal, double* values, const LinearSystem& system) const {
  constexpr int N = 3 * NB;
  const Discretisation::Cells& c = d_.cells();
  const std::vector<bool>& constrained = system.constrained();
  const bool tangent = values != nullptr;
  const unsigned int nq = c.nq;
  std::array<int, N> comp, base;  // cell dof i is component comp[i] of scalar base function base[i]
  for (int i = 0; i < N; ++i) comp[i] = static_cast<int>(c.component[i]), base[i] = static_cast<int>(c.base[i]);
  std::array<double, N> u_local, cell_internal, volume_gradient;
  std::array<double, N * N> cell_matrix;  // [i][j]: the blocks a <= b of base functions until mirrored
  double ag[NB][3][3][3];  // jxw A[ci][J][cj][.] . grad phi_b, so that K_ij = grad phi_i . ag[b_j][c_i][c_j]
  // Cell dof i is component i % 3 of base function i / 3 (deal.II's FESystem of three equal scalar
  // elements, checked): the tangent is then summed by 3 x 3 blocks with fixed loop bounds, which the
  // compiler unrolls. (Reading each dof's component and base function in the innermost loop took
  // most of the assembly's time.)
  bool node_major = true;
  for (int i = 0; i < N; ++i) node_major = node_major && comp[i] == i % 3 && base[i] == i / 3;
  if (!node_major) throw std::logic_error("the elasticity kernel expects the dofs of a cell node by node");
  const bool split_allowed = tangent && !full_tangent_requested();
  std::vector<Tensor2> F_at(nq);
  Tensor2 P;
  Tensor4 A;
  SplitTangent S;
  for (const unsigned int k : cells) {
    const types::global_dof_index* indices = c.dofs(k);
    const double* cell_jxw = c.jxw_of(k);
    const Tensor<1, 3>* cell_gradients = c.gradients_of(k);
    const Material& material = material_of(k);
    const bool split = split_allowed && material.has_split_tangent();
    for (int i = 0; i < N; ++i) u_local[i] = u[indices[i]];
    for (unsigned int q = 0; q < nq; ++q) {
      const Tensor<1, 3>* grad = cell_gradients + q * c.nbase;
      Tensor2& F = F_at[q];
      F = 0;
      for (int i = 0; i < N; ++i)
        for (int J = 0; J < 3; ++J) F[comp[i]][J] += u_local[i] * grad[base[i]][J];
      for (int a = 0; a < 3; ++a) F[a][a] += 1;
    }
    cell_internal.fill(0);
    if (tangent) cell_matrix.fill(0.0);
    // Mean dilatation: U(J) becomes U(theta) of the cell's volume ratio theta = v / V, its pressure
    // p = U'(theta) constant over the cell. One point (P1): theta = J, nothing changes.
    const bool dilatation = mean_dilatation_ && nq > 1;
    double reference_volume = 0, pressure = 0, pressure_stiffness = 0;
    if (dilatation) {
      double volume = 0;
      for (unsigned int q = 0; q < nq; ++q) {
        const double jxw = cell_jxw[q];
        const double j = determinant(F_at[q]);
        if (!(j > 0)) return false;
        volume += j * jxw;
        reference_volume += jxw;
      }
      material.volumetric(volume / reference_volume, pressure, pressure_stiffness);
      volume_gradient.fill(0);
    }
    for (unsigned int q = 0; q < nq; ++q) {
      const Tensor<1, 3>* grad = cell_gradients + q * c.nbase;
      const double jxw = cell_jxw[q];
      const Tensor2& F = F_at[q];
      if (split ? !material.evaluate_split(F, P, S) : !material.evaluate(F, P, tangent ? &A : nullptr)) return false;
      if (dilatation) {
        // Swap the point's volumetric stress U'(J) J F^-T for the cell's p J F^-T, and in the
        // tangent U''(J) J^2 F^-T x F^-T + U'(J) d2J for p d2J, d2J = J (F^-T x F^-T - F^-T o F^-1).
        const double j = determinant(F);
        const Tensor2 f_inv_t = split ? S.H : transpose(invert(F));
        double u1 = 0, u2 = 0;
        material.volumetric(j, u1, u2);
        const double excess = u1 - pressure;
        P -= excess * j * f_inv_t;
        if (split) {
          S.beta -= u2 * j * j + excess * j;
          S.gamma += excess * j;
        } else if (tangent)
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              for (int cc = 0; cc < 3; ++cc)
                for (int dd = 0; dd < 3; ++dd)
                  A[a][b][cc][dd] -= u2 * j * j * f_inv_t[a][b] * f_inv_t[cc][dd] +
                                     excess * j * (f_inv_t[a][b] * f_inv_t[cc][dd] - f_inv_t[a][dd] * f_inv_t[cc][b]);
        for (int i = 0; i < N; ++i)  // dv/du_i = int J F^-T : grad N_i
          volume_gradient[i] += j * (f_inv_t[comp[i]] * grad[base[i]]) * jxw;
      }
      for (int i = 0; i < N; ++i) {
        const Tensor<1, 3>& g = grad[base[i]];
        cell_internal[i] += (P[comp[i]][0] * g[0] + P[comp[i]][1] * g[1] + P[comp[i]][2] * g[2]) * jxw;
      }
      if (!tangent) continue;
      if (split) {
        add_split_tangent<NB>(grad, jxw, F, S, cell_matrix.data());
        continue;
      }
      for (int b = 0; b < NB; ++b) {
        const Tensor<1, 3>& g = grad[b];
        for (int ci = 0; ci < 3; ++ci)
          for (int J = 0; J < 3; ++J)
            for (int cj = 0; cj < 3; ++cj)
              ag[b][ci][cj][J] = jxw * (A[ci][J][cj][0] * g[0] + A[ci][J][cj][1] * g[1] + A[ci][J][cj][2] * g[2]);
      }
      for (int a = 0; a < NB; ++a) {
        const double g0 = grad[a][0], g1 = grad[a][1], g2 = grad[a][2];
        for (int ci = 0; ci < 3; ++ci) {
          double* row = &cell_matrix[std::size_t(3 * a + ci) * N];
          for (int b = a; b < NB; ++b)
            for (int cj = 0; cj < 3; ++cj) {
              const double* x = ag[b][ci][cj];
              row[3 * b + cj] += g0 * x[0] + g1 * x[1] + g2 * x[2];
            }
        }
      }
    }
    if (tangent) {
      for (int a = 1; a < NB; ++a)  // the blocks below the diagonal, K_(a,ci)(b,cj) = K_(b,cj)(a,ci)
        for (int b = 0; b < a; ++b)
          for (int ci = 0; ci < 3; ++ci)
            for (int cj = 0; cj < 3; ++cj)
              cell_matrix[std::size_t(3 * a + ci) * N + 3 * b + cj] =
                  cell_matrix[std::size_t(3 * b + cj) * N + 3 * a + ci];
      if (dilatation) {  // U''(theta)/V (dv/du)(dv/du)'
        const double scale = pressure_stiffness / reference_volume;
        for (int i = 0; i < N; ++i)
          for (int j = 0; j < N; ++j)
            cell_matrix[std::size_t(i) * N + j] += scale * volume_gradient[i] * volume_gradient[j];
      }
    }
    // Homogeneous constraints: constrained rows and columns are dropped (finish() puts their diagonal).
    const int* where = tangent ? system.cell_scatter(k) : nullptr;
    for (int i = 0; i < N; ++i) {
      if (internal) internal[indices[i]] += cell_internal[i];
      if (!constrained[indices[i]]) r[indices[i]] -= cell_internal[i];
      if (!tangent) continue;
      for (int j = 0; j < N; ++j)
        if (where[i * N + j] >= 0) values[where[i * N + j]] += cell_matrix[std::size_t(i) * N + j];
    }
  }
  return true;
}

bool ElasticityTerm::assemble_cells(const std::vector<unsigned int>& cells, const Vector<double>& u, double* r,
                                    double* internal, double* values, const LinearSystem& system) const {
  switch (d_.cells().nbase) {
    case 4: return assemble_fixed<4>(cells, u, r, internal, values, system);
    case 8: return assemble_fixed<8>(cells, u, r, internal, values, system);
    case 10: return assemble_fixed<10>(cells, u, r, internal, values, system);
    case 27: return assemble_fixed<27>(cells, u, r, internal, values, system);
    default: throw std::logic_error("no elasticity kernel for this element");
  }
}

namespace {
// The cores the calling thread may run on (a real-time session pins its solver away from the haptic
// thread's core).
int thread_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return static_cast<int>(std::thread::hardware_concurrency());
  return CPU_COUNT(&set);
}
}  // namespace

namespace {
// Cuts `cells` at the median of their centres along their longest extent. The cells of either side
// that share no DOF with the other side go to `first` and `second` (two threads may assemble them
// at once: they write disjoint rows), those along the cut to `cut`, each in the order of `cells`.
// `side` (per cell) and `touched` (per DOF) are scratch, left zero where they were.
void bisect(const std::vector<unsigned int>& cells, const std::vector<Point<3>>& centre, const Discretisation::Cells& c,
            std::vector<unsigned char>& side, std::vector<unsigned char>& touched, std::vector<unsigned int>& first,
            std::vector<unsigned int>& second, std::vector<unsigned int>& cut) {
  Point<3> low = centre[cells[0]], high = low;
  for (const unsigned int k : cells)
    for (int a = 0; a < 3; ++a) low[a] = std::min(low[a], centre[k][a]), high[a] = std::max(high[a], centre[k][a]);
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (high[a] - low[a] > high[axis] - low[axis]) axis = a;
  std::vector<unsigned int> order = cells;
  const auto below = [&](unsigned int x, unsigned int y) {
    return centre[x][axis] < centre[y][axis] || (centre[x][axis] == centre[y][axis] && x < y);
  };
  std::nth_element(order.begin(), order.begin() + order.size() / 2, order.end(), below);
  for (std::size_t i = 0; i < order.size(); ++i) side[order[i]] = i < order.size() / 2 ? 1 : 2;
  for (const unsigned int k : cells)
    for (unsigned int i = 0; i < c.n; ++i) touched[c.dofs(k)[i]] |= side[k];
  for (const unsigned int k : cells) {  // in cell order, as one thread would take them
    bool shared = false;
    for (unsigned int i = 0; i < c.n && !shared; ++i) shared = touched[c.dofs(k)[i]] == 3;
    (shared ? cut : side[k] == 1 ? first : second).push_back(k);
  }
  for (const unsigned int k : cells) {
    side[k] = 0;
    for (unsigned int i = 0; i < c.n; ++i) touched[c.dofs(k)[i]] = 0;
  }
}
}  // namespace

void ElasticityTerm::plan_threads() const {
  plan_ = {};
  planned_ = true;
  spare_core_ = thread_cores() > 2;  // the planning thread is the one that assembles
  const std::vector<unsigned int>& mine = d_.my_cells;
  if (d_.ranks > 1 || mine.size() < 2 * kCellsPerThread) {
    plan_[0] = mine;
    return;
  }
  std::vector<Point<3>> centre(d_.n_cells());
  {
    unsigned int k = 0;
    for (const auto& cell : d_.tria.active_cell_iterators()) centre[k++] = cell->center();
  }
  std::vector<unsigned char> side(d_.n_cells(), 0), touched(d_.n_dofs(), 0);
  std::vector<unsigned int> cut;
  bisect(mine, centre, d_.cells(), side, touched, plan_[0], plan_[1], cut);
  // The cells along the cut, a tenth of them on the 34,200-cell block, took a fifth of the
  // assembly's time on one thread (2.2 of 10.6 ms, 2026-12-02): they are cut again, across the
  // layer, and only those along that second cut are left to one thread (540 of 3,420 cells there;
  // 600 of 4,200 on the 42,000-cell block, whose assembly on two threads went from 10.0 to 9.6 ms).
  if (cut.size() >= 2 * kCellsPerThread) bisect(cut, centre, d_.cells(), side, touched, plan_[2], plan_[3], plan_[4]);
  else plan_[4] = std::move(cut);
}

bool ElasticityTerm::assemble(const AssemblyState& state, AssemblyTarget& target) {
  const LinearSystem& system = *target.system;
  material_of(0);                                // per-cell materials, the scatter map and the
  if (target.tangent) system.build_cell_scatter();  // threads' cells are built before the threads run
  if (!planned_) plan_threads();
  const auto run = [&](const std::vector<unsigned int>& cells) {
    return assemble_cells(cells, state.u, target.residual, target.internal, target.tangent, system);
  };
  if (plan_[1].empty()) return run(plan_[0]);
  // One thread takes the groups in turn: on one thread, and while the background factoriser holds a
  // core of a machine that has two, where a second thread would share that core with it (measured
  // on the anatomy with the 4 mm ball: 8.6 ms against 3.4 alone, where one thread takes about 6).
  // In turn or two at a time, each DOF gets its cells' contributions in the same order.
  if (threads_ < 2 || (!spare_core_ && system.tangent().background_factorising()))
    return std::all_of(plan_.begin(), plan_.end(), run);
  const auto pair = [&](const std::vector<unsigned int>& a, const std::vector<unsigned int>& b) {
    if (b.empty()) return run(a);
    return worker_.run([&] { return run(a); }, [&] { return run(b); });
  };
  return pair(plan_[0], plan_[1]) && pair(plan_[2], plan_[3]) && run(plan_[4]);
}

}  // namespace fetouch::fem

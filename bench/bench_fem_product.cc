// The product with the tangent, the unit of every linear solve's cost, against the machine's memory
// bandwidth (issue 38: a CG iteration within 3x the bandwidth floor).
//   build/release/bench/bench_fem --benchmark_filter='Stream|Product'
// BM_StreamTriad: a[i] = b[i] + s c[i] over three arrays far larger than the caches (STREAM's
// triad, McCalpin): bytes_per_second is the machine's sustained bandwidth (24 bytes an entry; the
// write-allocate read of a is not counted, as STREAM does not).
// BM_TangentProduct/nodes:N/vectors:V/blocked:B: y = K x for V vectors with the pattern of P1
// tetrahedra on an N^3 grid of nodes split into six tetrahedra each (Kuhn: 15 neighbours a node,
// 45 entries a row), one vector at a time (blocked:0) or four a pass (blocked:1, what the
// condensed compliance does). bytes_per_second counts the matrix (values and column indices) once a
// pass and every vector read and written: the floor is that byte count at the triad's bandwidth.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fem/tangent_system.h"

namespace {

using fetouch::fem::TangentSystem;

void BM_StreamTriad(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  for (auto _ : state) {
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + 3.0 * c[i];
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(24 * n));
}

// The 3-component pattern of a Kuhn-split N^3 node grid, every entry 1 off the diagonal.
void kuhn_grid(TangentSystem& k, int nodes) {
  const int offsets[15][3] = {{0, 0, 0},  {1, 0, 0},  {-1, 0, 0},  {0, 1, 0},  {0, -1, 0}, {0, 0, 1},   {0, 0, -1},
                              {1, 1, 0},  {-1, -1, 0}, {1, 0, 1},  {-1, 0, -1}, {0, 1, 1}, {0, -1, -1}, {1, 1, 1},
                              {-1, -1, -1}};
  const auto node = [nodes](int x, int y, int z) { return (z * nodes + y) * nodes + x; };
  std::vector<int> start{0}, columns;
  for (int z = 0; z < nodes; ++z)
    for (int y = 0; y < nodes; ++y)
      for (int x = 0; x < nodes; ++x)
        for (int c = 0; c < 3; ++c) {
          std::vector<int> row;
          for (const auto& o : offsets) {
            const int a = x + o[0], b = y + o[1], d = z + o[2];
            if (a < 0 || b < 0 || d < 0 || a >= nodes || b >= nodes || d >= nodes) continue;
            for (int e = 0; e < 3; ++e) row.push_back(3 * node(a, b, d) + e);
          }
          std::sort(row.begin(), row.end());
          columns.insert(columns.end(), row.begin(), row.end());
          start.push_back(static_cast<int>(columns.size()));
        }
  const int n = 3 * nodes * nodes * nodes;
  k.set_pattern(start, columns, TangentSystem::Method::amg, 0, n);
  k.zero();
  for (int i = 0; i < n; ++i)
    for (int p = start[i]; p < start[i + 1]; ++p) k.values()[p] = columns[p] == i ? 60.0 : -1.0;
}

void BM_TangentProduct(benchmark::State& state) {
  const int nodes = static_cast<int>(state.range(0)), vectors = static_cast<int>(state.range(1));
  const bool blocked = state.range(2) != 0;
  TangentSystem k;
  kuhn_grid(k, nodes);
  const std::size_t n = k.rows();
  std::vector<std::vector<double>> x(vectors, std::vector<double>(n)), y(vectors, std::vector<double>(n));
  std::vector<const double*> in;
  std::vector<double*> out;
  for (int j = 0; j < vectors; ++j) {
    for (std::size_t i = 0; i < n; ++i) x[j][i] = std::sin(0.001 * static_cast<double>(i) + j);
    in.push_back(x[j].data()), out.push_back(y[j].data());
  }
  for (auto _ : state) {
    if (blocked) {
      k.multiply_columns(in.data(), out.data(), vectors);
    } else {
      for (int j = 0; j < vectors; ++j) k.multiply(in[j], out[j]);
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  const double passes = blocked ? std::ceil(vectors / 4.0) : vectors;
  const double bytes = passes * 12.0 * static_cast<double>(k.nonzeros()) + 16.0 * vectors * static_cast<double>(n);
  state.SetBytesProcessed(static_cast<std::int64_t>(static_cast<double>(state.iterations()) * bytes));
  state.counters["dofs"] = static_cast<double>(n);
  state.counters["nonzeros"] = static_cast<double>(k.nonzeros());
  state.counters["per_vector"] = benchmark::Counter(static_cast<double>(vectors),
                                                       benchmark::Counter::kIsIterationInvariantRate |
                                                           benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_StreamTriad)->Arg(1 << 24)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TangentProduct)
    ->ArgNames({"nodes", "vectors", "blocked"})
    ->ArgsProduct({{19, 26, 33, 51}, {1, 6}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// One level of an algebraic multigrid hierarchy as reported (TangentSystem, build_aggregation_multigrid).
#pragma once

#include <cstddef>

namespace fetouch::fem {

struct MultigridLevel {
  std::size_t rows = 0, nonzeros = 0;
  std::size_t aggregates = 0;       // of this level's nodes (0 on the coarsest, and under GAMG)
  double nodes_per_aggregate = 0;   // this level's nodes that were aggregated, over the aggregates
};

}  // namespace fetouch::fem

// Building the deal.II Triangulation of a scene's mesh; see tissue_mesh.h for what is checked.
#pragma once

#include <deal.II/grid/tria.h>

#include "fem/tissue_mesh.h"

namespace fetouch::fem {

TissueMeshInfo build_tissue_mesh(const config::MeshSpec& spec, dealii::Triangulation<3>& tria);

}  // namespace fetouch::fem

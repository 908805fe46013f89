// Geometry queries on the body's boundary: the boundary point nearest a point in space, over the
// deformed (or reference) boundary faces, quadrilaterals split into two triangles, u linear between
// the vertices' values.
#pragma once

#include <deal.II/base/point.h>
#include <deal.II/lac/vector.h>

#include "fem/discretisation.h"

namespace fetouch::fem {

// The reference point X of the boundary whose deformed position X + u(X) is nearest x (or, with
// `u` null, whose reference position is).
dealii::Point<3> boundary_point_nearest(const Discretisation& d, const dealii::Point<3>& x, const dealii::Vector<double>* u);

}  // namespace fetouch::fem

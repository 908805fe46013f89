// The mesh readers: Gmsh (.msh, through Gmsh's API) and VTK unstructured grids (.vtu); the first
// byte picks. The same guard (meshes/mesh_file_checks.h) stands before the solver's readers.
#include "meshes/mesh_summary.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* format = fetouch::fuzz::pick(data, size, 2) == 0 ? ".msh" : ".vtu";
  try {
    fetouch::meshes::read_mesh_summary(fetouch::fuzz::as_file(data, size, format));
  } catch (const std::exception&) {
  }
  return 0;
}

// A Gmsh .msh file checked line by line before Gmsh reads it (issue 17): Gmsh's reader trusts the
// file and crashes on a physical name of dimension 4, an element naming an undefined node and the
// like (found by tests/fuzz/fuzz_mesh). Its own small library, so that both fetouch_meshes and the
// solver's reader in fem/ (which does not link fetouch_meshes) call it.
#pragma once

#include <filesystem>

namespace fetouch::meshes {

// Throws std::runtime_error "FILE:LINE: what is wrong; what was expected" unless `path` is an ASCII
// MSH 4.1 or 2.2 file whose sections are complete and consistent: $MeshFormat first; physical names
// of dimension 0 to 3; for 4.1, $Entities before $Nodes and every block's entity defined; node and
// element counts as declared (at most 5 * 10^7 nodes and 3 * 10^8 elements), finite coordinates,
// element types Gmsh numbers (1 to 15, 17, 29) with their node count, every node an element names
// defined. Other sections must be closed by their $End line.
void check_msh_structure(const std::filesystem::path& path);

}  // namespace fetouch::meshes

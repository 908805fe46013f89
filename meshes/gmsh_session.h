// One Gmsh session for the length of a call (Gmsh is global state), with Fetouch's settings.
#pragma once

#include <gmsh.h>

#include <algorithm>
#include <cstdlib>

namespace fetouch::meshes {

// A Gmsh session for one call (Gmsh is global state).
struct GmshSession {
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
  GmshSession() {
    gmsh::initialize();
    // FETOUCH_GMSH_LOG=N: Gmsh's own log on the terminal at verbosity N (5: every step's timing).
    const char* log = std::getenv("FETOUCH_GMSH_LOG");
    gmsh::option::setNumber("General.Terminal", log ? 1 : 0);
    gmsh::option::setNumber("General.Verbosity", log ? std::max(1, std::atoi(log)) : 1);
    // One thread: HXT in parallel gives a different mesh from run to run.
    gmsh::option::setNumber("General.NumThreads", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads1D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads2D", 1);
    gmsh::option::setNumber("Mesh.MaxNumThreads3D", 1);
  }
  ~GmshSession() { gmsh::finalize(); }
};

}  // namespace fetouch::meshes

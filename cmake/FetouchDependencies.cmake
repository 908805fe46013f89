# Every third-party package Fetouch uses, found through its own CMake config (or CMake's module).
# All come from Debian 12's packages; scripts/quickstart installs them.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(CLI11 CONFIG REQUIRED)

# MPI before VTK: Debian's VTK package refers to MPI::MPI_C.
find_package(MPI REQUIRED COMPONENTS C CXX)

# The parallel (OpenMPI) HDF5 that deal.II and PETSc use, so one libhdf5 ends up in the process.
set(HDF5_PREFER_PARALLEL ON)
find_package(HDF5 REQUIRED COMPONENTS C)
if(NOT HDF5_IS_PARALLEL)
  message(WARNING "Fetouch: the HDF5 found (${HDF5_VERSION}) is not the parallel build; "
                  "install libhdf5-openmpi-dev")
endif()
# zlib: checking compressed volume data (imaging/volume_io.cc) before VTK reads it.
find_package(ZLIB REQUIRED)
find_package(Threads REQUIRED)

find_package(VTK 9 REQUIRED COMPONENTS
  CommonCore CommonDataModel CommonExecutionModel
  IOImage IOXML IOLegacy
  ImagingCore ImagingGeneral FiltersCore FiltersGeneral FiltersModeling FiltersVerdict
  ChartsCore ViewsContext2D RenderingCore RenderingOpenGL2 RenderingContextOpenGL2
  RenderingFreeType InteractionStyle GUISupportQt RenderingAnnotation FiltersSources)
# The trainer window (app/trainer): Qt 5 widgets, and QTest for its tests; Debian's VTK Qt widget
# (libvtk9-qt-dev) is built against Qt 5.
find_package(Qt5 5.15 REQUIRED COMPONENTS Widgets Test)

find_package(deal.II 9.4 REQUIRED HINTS ${DEAL_II_DIR} $ENV{DEAL_II_DIR})
foreach(feature MPI PETSC METIS HDF5 GMSH)
  if(NOT DEAL_II_WITH_${feature})
    message(FATAL_ERROR "Fetouch needs deal.II configured with ${feature}; this one "
                        "(${DEAL_II_PATH}) is not. Debian's libdeal.ii-dev is.")
  endif()
endforeach()
message(STATUS "Fetouch: deal.II ${DEAL_II_PACKAGE_VERSION} with PETSc ${DEAL_II_PETSC_VERSION}")

# deal.II as one interface target. Its own DEAL_II_SETUP_TARGET links with CMake's plain signature
# and keeps the include directories private, which does not compose with our targets. Always the
# optimised library: the debug one checks every index and is about ten times slower.
if(NOT TARGET Fetouch::dealii)
  include(${DEAL_II_TARGET_CONFIG})
  add_library(Fetouch::dealii INTERFACE IMPORTED)
  target_include_directories(Fetouch::dealii SYSTEM INTERFACE ${DEAL_II_INCLUDE_DIRS})
  target_compile_definitions(Fetouch::dealii INTERFACE ${DEAL_II_USER_DEFINITIONS})
  target_link_libraries(Fetouch::dealii INTERFACE ${DEAL_II_TARGET_RELEASE})
endif()

if(FETOUCH_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
if(FETOUCH_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

# Gmsh's C++ API (libgmsh-dev ships no CMake package).
find_path(GMSH_INCLUDE_DIR gmsh.h REQUIRED)
find_library(GMSH_LIBRARY gmsh REQUIRED)
if(NOT TARGET Fetouch::gmsh)
  add_library(Fetouch::gmsh UNKNOWN IMPORTED)
  set_target_properties(Fetouch::gmsh PROPERTIES IMPORTED_LOCATION ${GMSH_LIBRARY}
                                                 INTERFACE_INCLUDE_DIRECTORIES ${GMSH_INCLUDE_DIR})
endif()

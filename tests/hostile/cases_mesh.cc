// Meshes: a scene whose tissue is a broken .vtu or .msh file, through `fetouch check`.
#include <string>
#include <utility>

#include "tests/hostile/hostile_case.h"

namespace fetouch::testing::hostile {

namespace {

std::string cube_vtu() { return read_text(source_dir() / "tests/data/unit_cube.vtu"); }
std::string cube_msh() { return read_text(source_dir() / "tests/data/unit_cube.msh"); }

// The block scene with its tissue from `mesh_file` (fixed on z = 0), checked.
Invocation check_scene_with_mesh(const fs::path& dir, const std::string& mesh_file, int exit_code = 2) {
  write_block_scene(dir, "scene.yaml", [&](std::string t) {
    t = replaced(t, "  generate:\n    shape: box\n    size_m: [0.10, 0.08, 0.05]\n    refinements: 2\n",
                 "  file: " + mesh_file + "\n");
    return replaced(t, "select: {physical_group: zmin}", "select: {plane: {point: [0, 0, 0], normal: [0, 0, 1]}}");
  });
  return {{"check", "scene.yaml"}, mesh_file, exit_code};
}

Case mesh(const std::string& name, const std::string& guards, const std::string& form, const std::string& file,
          const std::function<std::string()>& bytes, int exit_code = 2) {
  return {name, "mesh", guards, form, [=](const fs::path& dir) {
            write_text(dir / file, bytes());
            return check_scene_with_mesh(dir, file, exit_code);
          }};
}

Case vtu_edit(const std::string& name, const std::string& guards, const std::string& form, const std::string& from,
              const std::string& to) {
  return mesh(name, guards, form, "tissue.vtu", [=] { return replaced(cube_vtu(), from, to); });
}

Case msh_edit(const std::string& name, const std::string& guards, const std::string& form, const std::string& from,
              const std::string& to) {
  return mesh(name, guards, form, "tissue.msh", [=] { return replaced(cube_msh(), from, to); });
}

const char* const kConnectivity = "0 1 2 6  0 2 3 6  0 3 7 6  0 7 4 6  0 4 5 6  0 5 1 6";
const char* const kPoints = "0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1";

}  // namespace

std::vector<Case> mesh_cases() {
  std::vector<Case> c;
  c.push_back(mesh("ValidVtu", "valid", "name", "tissue.vtu", cube_vtu, 0));
  c.push_back(mesh("ValidMsh", "valid", "name", "tissue.msh", cube_msh, 0));
  // .vtu: cells that do not fit their points (SIGSEGV before issue 17).
  c.push_back(vtu_edit("VtuConnectivityPastThePoints", "crash", "wrong shape", kConnectivity, "0 1 2 6  0 2 3 6  0 3 7 6  0 7 4 6  0 4 5 6  0 5 1 600000"));
  c.push_back(vtu_edit("VtuNegativeConnectivity", "crash", "wrong shape", kConnectivity, "0 1 2 6  0 2 3 6  0 3 7 6  0 7 4 6  0 4 5 6  0 5 1 -7"));
  c.push_back(vtu_edit("VtuTetrahedronOfThreePoints", "crash", "wrong shape", "4 8 12 16 20 24", "3 7 11 15 19 23"));
  c.push_back(vtu_edit("VtuOffsetsPastConnectivity", "crash", "wrong shape", "4 8 12 16 20 24", "4 8 12 16 20 2400"));
  c.push_back(vtu_edit("VtuOffsetsDecreasing", "crash", "wrong shape", "4 8 12 16 20 24", "4 8 12 16 24 20"));
  c.push_back(vtu_edit("VtuFewerTypesThanCells", "crash", "wrong shape", "10 10 10 10 10 10", "10 10 10"));
  c.push_back(vtu_edit("VtuTrianglesOnly", "unclear", "wrong shape", "10 10 10 10 10 10", "5 5 5 5 5 5"));
  c.push_back(vtu_edit("VtuNaNCoordinate", "nonsense", "non-finite", kPoints, "0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 nan  1 1 1  0 1 1"));
  c.push_back(vtu_edit("VtuInfiniteCoordinate", "nonsense", "non-finite", kPoints, "0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 inf  1 1 1  0 1 1"));
  c.push_back(vtu_edit("VtuCoordinates1e300", "nonsense", "absurd", kPoints, "0 0 0  1e300 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1"));
  c.push_back(vtu_edit("VtuInMillimetres", "nonsense", "absurd", kPoints, "0 0 0  100 0 0  100 100 0  0 100 0  0 0 100  100 0 100  100 100 100  0 100 100"));
  c.push_back(vtu_edit("VtuAllPointsTheSame", "nonsense", "absurd", kPoints, "0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0  0 0 0"));
  c.push_back(vtu_edit("VtuFewerPointsThanDeclared", "crash", "truncated", kPoints, "0 0 0  1 0 0  1 1 0  0 1 0"));
  c.push_back(vtu_edit("VtuPointCountOfATrillion", "hang", "huge", "NumberOfPoints=\"8\"", "NumberOfPoints=\"1000000000000\""));
  c.push_back(vtu_edit("VtuCellCountOfATrillion", "hang", "huge", "NumberOfCells=\"6\"", "NumberOfCells=\"1000000000000\""));
  c.push_back(vtu_edit("VtuNegativePointCount", "crash", "wrong shape", "NumberOfPoints=\"8\"", "NumberOfPoints=\"-8\""));
  c.push_back(vtu_edit("VtuTwoComponentPoints", "crash", "wrong shape", "NumberOfComponents=\"3\"", "NumberOfComponents=\"2\""));
  c.push_back(vtu_edit("VtuWordsForNumbers", "unclear", "wrong shape", kPoints, "a b c  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1"));
  c.push_back(vtu_edit("VtuBinaryDataCutShort", "crash", "truncated", "format=\"ascii\">\n          0 0 0", "format=\"binary\">\n          AAAA"));
  c.push_back(vtu_edit("VtuUnknownDataType", "unclear", "wrong shape", "type=\"Float64\"", "type=\"Float128\""));
  c.push_back(vtu_edit("VtuPolyDataInside", "unclear", "wrong shape", "type=\"UnstructuredGrid\"", "type=\"PolyData\""));
  for (int quarter = 1; quarter <= 3; ++quarter)
    c.push_back(mesh("VtuTruncatedAt" + std::to_string(quarter * 25) + "Percent", "unclear", "truncated", "tissue.vtu", [quarter] {
      const std::string t = cube_vtu();
      return t.substr(0, t.size() * static_cast<std::size_t>(quarter) / 4);
    }));
  c.push_back(mesh("VtuEmpty", "unclear", "truncated", "tissue.vtu", [] { return std::string(); }));
  c.push_back(mesh("VtuGarbage", "unclear", "malformed", "tissue.vtu", [] { return garbage(8192, 3); }));
  c.push_back(mesh("VtuThatIsAMsh", "unclear", "malformed", "tissue.vtu", cube_msh));
  c.push_back(mesh("VtuEntityBomb", "hang", "malformed", "tissue.vtu", [] {
    std::string t = "<?xml version=\"1.0\"?>\n<!DOCTYPE VTKFile [\n<!ENTITY a \"aaaaaaaaaa\">\n";
    for (char e = 'b'; e <= 'k'; ++e) {
      std::string refs;
      for (int i = 0; i < 10; ++i) refs += std::string("&") + static_cast<char>(e - 1) + ";";
      t += std::string("<!ENTITY ") + e + " \"" + refs + "\">\n";
    }
    return t + "]>\n<VTKFile type=\"UnstructuredGrid\">&k;</VTKFile>\n";
  }));
  c.push_back({"VtuSparseFourGigabytes", "mesh", "hang", "huge", [](const fs::path& dir) {
                 make_sparse(dir / "tissue.vtu", 4ull << 30);
                 return check_scene_with_mesh(dir, "tissue.vtu");
               }});
  c.push_back({"VtuIsAFifo", "mesh", "hang", "special file", [](const fs::path& dir) {
                 make_fifo(dir / "tissue.vtu");
                 return check_scene_with_mesh(dir, "tissue.vtu");
               }});
  c.push_back({"VtuIsAFolder", "mesh", "unclear", "special file", [](const fs::path& dir) {
                 fs::create_directories(dir / "tissue.vtu");
                 return check_scene_with_mesh(dir, "tissue.vtu");
               }});

  // .msh (an abort on Gmsh's exceptions before issue 17).
  c.push_back(msh_edit("MshUnknownVersion", "crash", "malformed", "4.1 0 8", "9.9 0 8"));
  c.push_back(msh_edit("MshNoNodes", "crash", "wrong shape", "$Nodes\n1 8 1 8", "$Nodes\n0 0 0 0"));
  c.push_back(msh_edit("MshUndefinedNode", "crash", "wrong shape", "$Nodes\n1 8 1 8\n3 1 0 8\n1\n", "$Nodes\n1 8 1 80\n3 1 0 8\n71\n"));
  c.push_back(msh_edit("MshNaNCoordinate", "nonsense", "non-finite", "1 0 0\n1 1 0", "1 0 nan\n1 1 0"));
  c.push_back(msh_edit("MshNodeCountOfATrillion", "hang", "huge", "$Nodes\n1 8 1 8\n3 1 0 8", "$Nodes\n1 1000000000000 1 1000000000000\n3 1 0 1000000000000"));
  c.push_back(msh_edit("MshAsciiFlagWrong", "crash", "malformed", "4.1 0 8", "4.1 1 8"));
  c.push_back(msh_edit("MshWordsInNodes", "crash", "malformed", "1 0 0\n1 1 0", "one zero zero\n1 1 0"));
  c.push_back(mesh("MshGarbageAfterHeader", "crash", "malformed", "tissue.msh", [] { return "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" + garbage(4096, 5); }));
  c.push_back(mesh("MshOnlyTheHeader", "crash", "truncated", "tissue.msh", [] { return std::string("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"); }));
  for (int quarter = 1; quarter <= 3; ++quarter)
    c.push_back(mesh("MshTruncatedAt" + std::to_string(quarter * 25) + "Percent", "crash", "truncated", "tissue.msh", [quarter] {
      const std::string t = cube_msh();
      return t.substr(0, t.size() * static_cast<std::size_t>(quarter) / 4);
    }));
  c.push_back(mesh("MshThatIsAGeoScript", "crash", "malformed", "tissue.msh", [] {
    return std::string("SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1, 1};\nSystemCall \"touch hostile_marker\";\n");
  }));
  c.push_back(mesh("MshEmpty", "unclear", "truncated", "tissue.msh", [] { return std::string(); }));
  c.push_back(mesh("MshThatIsAVtu", "unclear", "malformed", "tissue.msh", cube_vtu));
  c.push_back({"MshIsDevZero", "mesh", "hang", "special file", [](const fs::path& dir) {
                 fs::create_symlink("/dev/zero", dir / "tissue.msh");
                 return check_scene_with_mesh(dir, "tissue.msh");
               }});
  c.push_back({"MeshWithUnknownExtension", "mesh", "unclear", "name", [](const fs::path& dir) {
                 write_text(dir / "tissue.stl", "solid x\nendsolid x\n");
                 return check_scene_with_mesh(dir, "tissue.stl");
               }});
  return c;
}

}  // namespace fetouch::testing::hostile

// ParaView's collection file (.pvd): a time series of VTK files, each with its time.
#pragma once

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fetouch::app {

// `files` are (time in s, path relative to the .pvd's folder). Throws std::runtime_error naming the file.
inline void write_pvd(const std::filesystem::path& pvd, const std::vector<std::pair<double, std::string>>& files) {
  std::ofstream p(pvd);
  p << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [t, file] : files)
    p << "    <DataSet timestep=\"" << t << "\" group=\"\" part=\"0\" file=\"" << file << "\"/>\n";
  p << "  </Collection>\n</VTKFile>\n";
  if (!p) throw std::runtime_error("cannot write " + pvd.string());
}

}  // namespace fetouch::app

// The file an error is about, first on its line (the README's error contract): a message that
// already starts with a file ("take.h5: dataset time_s ...") is left as it is; any other gets
// `file` in front ("scene.yaml: deal.II could not generate the mesh").
#pragma once

#include <filesystem>
#include <string>

namespace fetouch::app {

inline std::string naming(const std::string& file, const std::string& message) {
  const std::size_t colon = message.find(": ");
  if (colon != std::string::npos && colon > 0) {
    const std::string head = message.substr(0, message.find_first_of(": (", 0) < colon ? message.find_first_of(":(", 0) : colon);
    std::error_code error;
    const std::filesystem::path path(head.substr(0, head.find(' ')));
    if (path.has_extension() || std::filesystem::exists(path, error)) return message;
  }
  return file + ": " + message;
}

}  // namespace fetouch::app

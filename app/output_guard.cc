#include "app/output_guard.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace fetouch::app {

namespace fs = std::filesystem;

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code error;
  if (fs::exists(a, error) && fs::exists(b, error)) return fs::equivalent(a, b, error);
  const fs::path x = fs::weakly_canonical(fs::absolute(a, error), error);
  const fs::path y = fs::weakly_canonical(fs::absolute(b, error), error);
  return x == y;
}

void refuse_overwriting(const std::vector<fs::path>& written, const std::vector<NamedInput>& inputs,
                        const fs::path& folder, const std::function<bool(const std::string&)>& written_in_folder) {
  std::error_code error;
  if (!folder.empty() && fs::exists(folder, error) && !fs::is_directory(folder, error))
    throw std::invalid_argument("--out: " + folder.string() + " is a file, not a folder; name a folder for the outputs");
  for (const auto& [input, role] : inputs) {
    if (input.empty()) continue;
    for (const fs::path& output : written)
      if (same_file(output, input))
        throw std::invalid_argument("--out: writing " + output.string() + " would overwrite " + role + " " +
                                    input.string() + "; choose another output");
    if (!folder.empty() && written_in_folder && same_file(input.parent_path().empty() ? "." : input.parent_path(), folder) &&
        written_in_folder(input.filename().string()))
      throw std::invalid_argument("--out: the folder " + folder.string() + " holds " + role + " " + input.string() +
                                  ", which this command would overwrite; choose another output folder");
  }
}

fs::path partial_path(const fs::path& path) {
  fs::path partial = path;
  partial.replace_filename(path.stem().string() + ".partial" + path.extension().string());
  return partial;
}

void replace_when_written(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  // A detached header names its data file by its own name, which a rename would not follow.
  if (path.extension() == ".mhd" || path.extension() == ".nhdr") return write(path);
  // The process id keeps two commands writing the same output from sharing a temporary file.
  fs::path temporary = path;
  temporary.replace_filename("." + path.stem().string() + ".writing" + std::to_string(::getpid()) + path.extension().string());
  try {
    write(temporary);
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    // The writer knew only the temporary name: the user gave `path`, and that is what they look for.
    std::string message = e.what();
    bool named = false;
    for (const std::string& name : {temporary.string(), temporary.filename().string()})
      for (std::size_t at = message.find(name); !name.empty() && at != std::string::npos; at = message.find(name, at)) {
        message.replace(at, name.size(), name == temporary.string() ? path.string() : path.filename().string());
        named = true;
      }
    if (!named) throw;
    throw std::runtime_error(message);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    fs::remove(temporary, error);
    throw std::runtime_error(path.string() + ": cannot be written (" + error.message() + ")");
  }
}

void write_text_file(const fs::path& path, const std::string& text) {
  replace_when_written(path, [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw std::runtime_error(path.string() + ": cannot be written (" + std::strerror(errno) + ")");
  });
}

}  // namespace fetouch::app

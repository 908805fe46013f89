#include "app/output_guard.h"

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

}  // namespace fetouch::app

// Outputs written whole or not at all (app/output_guard.h, issue 17): a writer that fails leaves the
// earlier file byte for byte and no temporary file behind; one that succeeds replaces it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "app/output_guard.h"

namespace fetouch::app {
namespace {

namespace fs = std::filesystem;

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(ReplaceWhenWritten, AFailedWriteLeavesTheEarlierFile) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replace_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path file = dir / "summary.json";
  write_text_file(file, "first");
  EXPECT_EQ(contents(file), "first");
  fs::path used;
  EXPECT_THROW(replace_when_written(file,
                                    [&](const fs::path& temporary) {
                                      used = temporary;
                                      std::ofstream(temporary) << "half of the sec";
                                      throw std::runtime_error("the computation failed");
                                    }),
               std::runtime_error);
  EXPECT_EQ(contents(file), "first");
  EXPECT_EQ(used.parent_path(), dir);             // beside it, so the rename stays on one file system
  EXPECT_EQ(used.extension(), file.extension());  // writers that go by the extension still see it
  EXPECT_FALSE(fs::exists(used));
  write_text_file(file, "second");
  EXPECT_EQ(contents(file), "second");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temporary left
  // A folder that cannot be written: an error naming the file, nothing changed.
  EXPECT_THROW(write_text_file(dir / "missing" / "summary.json", "x"), std::runtime_error);
  EXPECT_EQ(partial_path(dir / "recording.h5"), dir / "recording.partial.h5");
  fs::remove_all(dir);
}

// A writer knows only the temporary file it fills: its error names the file the user gave (it named
// ".out.writing24961.png", issue 41).
TEST(ReplaceWhenWritten, AWritersErrorNamesThePathGivenNotTheTemporaryFile) {
  const fs::path dir = fs::temp_directory_path() / ("fetouch_replace_name_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "out.png";
  try {
    replace_when_written(file, [](const fs::path& temporary) {
      throw std::runtime_error("vtkPNGWriter: cannot write " + temporary.string() + " (no space)");
    });
    FAIL() << "the writer's error was lost";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what, "vtkPNGWriter: cannot write " + file.string() + " (no space)");
  }
  EXPECT_TRUE(fs::is_empty(dir));  // nothing left behind
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fetouch::app

// libFuzzer harnesses (issue 17): each hands fuzzed bytes to one of Fetouch's readers of outside
// files, as a file with the reader's extension. A reader may refuse an input by throwing a
// std::exception (what the commands catch and report); anything else is a finding: a crash, a
// sanitizer report, a hang past -timeout, memory past -rss_limit_mb, or another exception type
// (which fetouch's handlers would not catch).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace fetouch::fuzz {

// `size` bytes written to this process's scratch file NAME.EXTENSION in the temporary folder.
inline std::filesystem::path as_file(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("fetouch_fuzz_" + std::to_string(::getpid()) + extension);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// The first byte picks one of `count` formats; the rest is the file.
inline std::size_t pick(const std::uint8_t*& data, std::size_t& size, std::size_t count) {
  if (size == 0) return 0;
  const std::size_t choice = data[0] % count;
  ++data, --size;
  return choice;
}

}  // namespace fetouch::fuzz

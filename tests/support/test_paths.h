#pragma once
// Where a test program finds the repository, its test data and the programs it runs.
//
// The values live in one source file that CMake writes into the build folder (tests/CMakeLists.txt,
// fetouch_test_paths), not in compile definitions: a test source's compile line then names no
// absolute path, so ccache (with the source tree as its base directory) gives a clone in another
// folder the objects an earlier clone compiled, and only that one small file is compiled again.
// The names are the macros the tests have always used; each is a `const char*`.

namespace fetouch::test_paths {
extern const char source_dir[];            // the repository
extern const char test_data_dir[];         // the repository's tests/ folder
extern const char fetouch_binary[];        // the `fetouch` program of this build
extern const char mpiexec[];               // mpiexec (or mpirun) as CMake found it
extern const char standin_libhd[];         // the stand-in libHD.so
extern const char standin_broken_libhd[];  // the stand-in without hdEndFrame
extern const char preset[];                // the build folder's name: release, asan, ...
}  // namespace fetouch::test_paths

#define FETOUCH_SOURCE_DIR (::fetouch::test_paths::source_dir)
#define FETOUCH_TEST_DATA_DIR (::fetouch::test_paths::test_data_dir)
#define FETOUCH_BINARY (::fetouch::test_paths::fetouch_binary)
#define FETOUCH_MPIEXEC (::fetouch::test_paths::mpiexec)
#define STANDIN_LIBHD (::fetouch::test_paths::standin_libhd)
#define STANDIN_BROKEN_LIBHD (::fetouch::test_paths::standin_broken_libhd)
#define FETOUCH_PRESET (::fetouch::test_paths::preset)

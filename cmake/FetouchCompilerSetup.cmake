# Compiler launcher, warnings and sanitizers shared by every Fetouch target.

# ccache makes the second build of an unchanged tree (and CI on a machine that built before) fast.
# Its base directory is the source tree, so that the compile lines' absolute paths (-I/path/to/clone/...)
# are hashed relative to it and a clone in another folder (a fresh clone for CI or the README's test
# command) finds what this one compiled; with ccache's default (no base directory) it found nothing.
# CCACHE_NOHASHDIR: with -g (the asan and fuzz presets) ccache would also hash the build folder, so a
# clone elsewhere found none of those objects. The price: an object taken from the cache keeps the
# build folder it was first compiled in as its debug information's compilation folder, so a
# sanitizer report or gdb names the right file (its path relative to the base directory) under that
# first clone's folder.
find_program(FETOUCH_CCACHE ccache)
if(FETOUCH_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(FETOUCH_CCACHE_LAUNCHER env CCACHE_BASEDIR=${CMAKE_SOURCE_DIR} CCACHE_NOHASHDIR=1 ${FETOUCH_CCACHE})
  set(CMAKE_C_COMPILER_LAUNCHER ${FETOUCH_CCACHE_LAUNCHER})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${FETOUCH_CCACHE_LAUNCHER})
  message(STATUS "Fetouch: compiling through ${FETOUCH_CCACHE} (base directory ${CMAKE_SOURCE_DIR})")
endif()

# Warnings for our own code only; applied per target by fetouch_target_defaults().
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(FETOUCH_WARNINGS -Wall -Wextra -Wpedantic -Wshadow=local -Wno-unused-parameter)
else()  # clang (the fuzz preset)
  set(FETOUCH_WARNINGS -Wall -Wextra -Wpedantic -Wno-unused-parameter)
endif()

if(FETOUCH_SANITIZE)
  # -fno-sanitize-recover makes any undefined behaviour fail the test that triggers it.
  set(FETOUCH_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=all
                              -fno-omit-frame-pointer)
  add_compile_options(${FETOUCH_SANITIZER_FLAGS})
  add_link_options(${FETOUCH_SANITIZER_FLAGS})
endif()

# The libFuzzer harnesses (tests/fuzz, the `fuzz` preset: clang). Every library is instrumented
# for coverage and the sanitizers; only the harnesses link libFuzzer's main.
if(FETOUCH_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "FETOUCH_FUZZ needs clang (Debian: clang libfuzzer-14-dev); use the fuzz preset")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# fetouch_target_defaults(<target>): warnings and the repository root as include directory.
function(fetouch_target_defaults target)
  target_compile_options(${target} PRIVATE ${FETOUCH_WARNINGS})
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "INTERFACE_LIBRARY")
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
  else()
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  endif()
endfunction()

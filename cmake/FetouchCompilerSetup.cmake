# Compiler launcher, warnings and sanitizers shared by every Fetouch target.

# ccache makes the second build of an unchanged tree (and CI on a machine that built before) fast.
find_program(FETOUCH_CCACHE ccache)
if(FETOUCH_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_C_COMPILER_LAUNCHER ${FETOUCH_CCACHE})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${FETOUCH_CCACHE})
  message(STATUS "Fetouch: compiling through ${FETOUCH_CCACHE}")
endif()

# Warnings for our own code only; applied per target by fetouch_target_defaults().
set(FETOUCH_WARNINGS -Wall -Wextra -Wpedantic -Wshadow=local -Wno-unused-parameter)

if(FETOUCH_SANITIZE)
  # -fno-sanitize-recover makes any undefined behaviour fail the test that triggers it.
  set(FETOUCH_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=all
                              -fno-omit-frame-pointer)
  add_compile_options(${FETOUCH_SANITIZER_FLAGS})
  add_link_options(${FETOUCH_SANITIZER_FLAGS})
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

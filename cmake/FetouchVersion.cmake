# Generates ${CMAKE_BINARY_DIR}/generated/app/build_info.cc at every build, rewriting it only when
# the git revision changes, so `fetouch --version` is never stale and an unchanged tree relinks nothing.

set(FETOUCH_BUILD_INFO_CC ${CMAKE_BINARY_DIR}/generated/app/build_info.cc)
add_custom_target(fetouch_build_info_gen
  COMMAND ${CMAKE_COMMAND}
          -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
          -DOUTPUT=${FETOUCH_BUILD_INFO_CC}
          -DFETOUCH_VERSION=${PROJECT_VERSION}
          -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
          -DCOMPILER=${CMAKE_CXX_COMPILER_ID}-${CMAKE_CXX_COMPILER_VERSION}
          -DDEAL_II_VERSION=${DEAL_II_PACKAGE_VERSION}
          -DVTK_VERSION=${VTK_VERSION}
          -P ${PROJECT_SOURCE_DIR}/cmake/WriteBuildInfo.cmake
  BYPRODUCTS ${FETOUCH_BUILD_INFO_CC}
  COMMENT "Checking git revision"
  VERBATIM)

// Facts about this build, generated at build time (cmake/WriteBuildInfo.cmake).
#pragma once

namespace fetouch::app {
extern const char* const kVersion;      // "0.1.0"
extern const char* const kGitRevision;  // `git describe --always --dirty`
extern const char* const kBuildType;
extern const char* const kCompiler;
extern const char* const kDealIIVersion;
extern const char* const kVtkVersion;
}  // namespace fetouch::app

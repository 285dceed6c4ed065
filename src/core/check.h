// PATCHSCAN_DCHECK(condition, what): a contract between two parts of the library, stated
// where it is relied on. A debug build (NDEBUG not defined) and the sanitizer build
// (PATCHSCAN_SANITIZE, which defines PATCHSCAN_CHECKS) check it: a broken contract prints
// the condition, `what` and file:line to stderr and aborts, so the test that reached it
// fails there and then. A release build compiles the check out without evaluating it.
//
// A contract is not input validation: a malformed scene is reported to the user as an
// error (scene/source_error.h, render/status.h); a DCHECK that fires is a bug.
#pragma once

#include <cstdio>
#include <cstdlib>

#if !defined(NDEBUG) || defined(PATCHSCAN_CHECKS)
#define PATCHSCAN_CHECKS_ON 1
#else
#define PATCHSCAN_CHECKS_ON 0
#endif

namespace patchscan::detail {

[[noreturn]] inline void CheckFailed(const char* condition, const char* what, const char* file, int line) {
  std::fprintf(stderr, "%s:%d: contract broken: %s (%s)\n", file, line, what, condition);
  std::fflush(stderr);
  std::abort();
}

}  // namespace patchscan::detail

#if PATCHSCAN_CHECKS_ON
#define PATCHSCAN_DCHECK(condition, what) \
  ((condition) ? static_cast<void>(0) : ::patchscan::detail::CheckFailed(#condition, what, __FILE__, __LINE__))
#else
// Not evaluated, but still compiled, so that a check cannot rot in release builds.
#define PATCHSCAN_DCHECK(condition, what) static_cast<void>(sizeof(static_cast<bool>(condition)))
#endif

// PATCHSCAN_DCHECK (core/check.h): checked in debug and sanitizer builds, where a broken
// contract aborts naming itself; compiled out of release builds, condition unevaluated.
#include <gtest/gtest.h>

#include "core/check.h"
#include "tracker/newton.h"

namespace patchscan {
namespace {

TEST(Check, HoldingContractPasses) {
  int evaluated = 0;
  PATCHSCAN_DCHECK(++evaluated == 1, "evaluated once where checks are on");
  EXPECT_EQ(evaluated, PATCHSCAN_CHECKS_ON ? 1 : 0);
}

TEST(CheckDeathTest, BrokenContractAbortsNamingItself) {
  if (!PATCHSCAN_CHECKS_ON) GTEST_SKIP() << "checks are compiled out of this build";
  EXPECT_DEATH(PATCHSCAN_DCHECK(1 + 1 == 3, "arithmetic"), "contract broken: arithmetic \\(1 \\+ 1 == 3\\)");
}

TEST(CheckDeathTest, NewtonRefusesAnEmptyBracket) {
  if (!PATCHSCAN_CHECKS_ON) GTEST_SKIP() << "checks are compiled out of this build";
  const auto f = [](double t, double* v, double* d) { *v = t, *d = 1.0; };
  EXPECT_DEATH(SolveNewton1(f, 0.5, 1.0, 0.0, 1e-12), "bracket");
}

}  // namespace
}  // namespace patchscan

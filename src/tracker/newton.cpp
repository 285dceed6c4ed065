#include "tracker/newton.h"

namespace patchscan {

const char* ToString(NewtonStatus s) {
  switch (s) {
    case NewtonStatus::Converged: return "converged";
    case NewtonStatus::IterationCap: return "iteration cap";
    case NewtonStatus::Singular: return "singular";
    case NewtonStatus::LeftDomain: return "left domain";
  }
  return "?";
}

}  // namespace patchscan

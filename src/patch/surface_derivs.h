// What a surface evaluation returns: position and partial derivatives at (u,v).
#pragma once

#include "patch/geometry.h"

namespace patchscan {

// How much of SurfaceDerivs an evaluation fills in; higher orders include lower ones.
// Fields beyond the requested order are left untouched (not zeroed).
enum class DerivOrder { Position = 0, First = 1, Second = 2 };

// Position and derivatives of S(u,v) in one space (object or screen, as the producer says).
struct SurfaceDerivs {
  Vec3 p, dpdu, dpdv;
  Vec3 d2pdu2, d2pduv, d2pdv2;
};

inline bool Wants(DerivOrder order, DerivOrder level) {
  return static_cast<int>(order) >= static_cast<int>(level);
}

}  // namespace patchscan

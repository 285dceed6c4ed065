#include "tracker/theta_tracker.h"

namespace patchscan {

namespace {

// The world normal n = ±(L p_u) × (L p_v) (not unit) and its (u,v) derivatives, with the
// world tangents. (L a) × (L b) = det L · L^-T (a × b): the world normal up to the sign of
// det L, which FragmentAt's L^-T (a × b) keeps.
struct WorldNormal {
  Vec3 pu, pv, n, nu, nv;
};
WorldNormal WorldNormalOf(const SurfaceDerivs& o, const ThetaFrame& frame) {
  WorldNormal w;
  if (frame.worldIsObject) {
    w.pu = o.dpdu, w.pv = o.dpdv;
    w.n = w.pu.cross(w.pv);
    w.nu = o.d2pdu2.cross(w.pv) + w.pu.cross(o.d2pduv);
    w.nv = o.d2pduv.cross(w.pv) + w.pu.cross(o.d2pdv2);
    return w;
  }
  const auto L = frame.World().linear();
  w.pu = L * o.dpdu;
  w.pv = L * o.dpdv;
  const Vec3 puu = L * o.d2pdu2, puv = L * o.d2pduv, pvv = L * o.d2pdv2;
  const double sign = L.determinant() < 0.0 ? -1.0 : 1.0;
  w.n = sign * w.pu.cross(w.pv);
  w.nu = sign * (puu.cross(w.pv) + w.pu.cross(puv));
  w.nv = sign * (puv.cross(w.pv) + w.pu.cross(pvv));
  return w;
}

// TableFunction at `angle`, or (null) at the point's own angle θ: (cos θ, sin θ) = (S, T) /
// |(S, T)|, with the normal, the view ray and s found once for both (NaN where the normal
// is across the scan plane).
TableResidual TableAt(const SurfaceDerivs& o, const ThetaFrame& frame, const Vec2* angle) {
  const Vec3 p = frame.worldIsObject ? o.p : Vec3(frame.World() * o.p);
  const WorldNormal w = WorldNormalOf(o, frame);
  const Vec3 &n = w.n, &nu = w.nu, &nv = w.nv, &pu = w.pu, &pv = w.pv;
  // The view ray r and its derivatives along the surface (zero in orthographic).
  Vec3 r, ru = Vec3::Zero(), rv = Vec3::Zero();
  if (frame.orthographic) {
    r = frame.forward;
  } else {
    const Vec3 e = p - frame.eye;
    const double rho = e.norm();
    r = e / rho;
    ru = (pu - r * r.dot(pu)) / rho;
    rv = (pv - r * r.dot(pv)) / rho;
  }
  // The scan plane's unit normal q = right × r / |right × r|, and s = r × q.
  const Vec3 m = frame.right.cross(r);
  const double mu = m.norm();
  const Vec3 q = m / mu;
  auto dq = [&](const Vec3& dr) {
    const Vec3 dm = frame.right.cross(dr);
    return Vec3((dm - q * q.dot(dm)) / mu);
  };
  const Vec3 qu = dq(ru), qv = dq(rv);
  const Vec3 s = r.cross(q);
  const Vec3 su = ru.cross(q) + r.cross(qu), sv = rv.cross(q) + r.cross(qv);
  const Vec2 own = angle ? Vec2::Zero() : Vec2(n.dot(s), -n.dot(r));
  const Vec2 a = angle ? *angle : Vec2(own / own.norm());
  const double c = a.x(), sn = a.y();
  const Vec3 d = sn * s + c * r;
  const Vec3 du = sn * su + c * ru, dv = sn * sv + c * rv;
  const double len = n.norm();
  const double G = n.dot(d);
  const double Gu = nu.dot(d) + n.dot(du), Gv = nv.dot(d) + n.dot(dv);
  // d(G/|N|) = dG/|N| - G (N·dN)/|N|³.
  TableResidual out;
  out.g = G / len;
  out.grad = Vec2(Gu / len - G * n.dot(nu) / (len * len * len), Gv / len - G * n.dot(nv) / (len * len * len));
  out.along = n.dot(c * s - sn * r) / len;
  out.t = -n.dot(r) / len;
  return out;
}

}  // namespace

TableResidual TableFunction(const SurfaceDerivs& o, const ThetaFrame& frame, const Vec2& angle) {
  return TableAt(o, frame, &angle);
}

double TurnFunction(const SurfaceDerivs& object, const Vec2& gradY, const ThetaFrame& frame) {
  // At the point's own angle θ, G_θ = 0 and G_φ/|N| = ρ sin(φ - θ) with ρ the in-plane part
  // of the unit normal, so G_θ's gradient at fixed φ = θ is -ρ ∇θ.
  return TurnRate(TableAt(object, frame, nullptr), gradY);
}

Vec3 NormalSlope(const SurfaceDerivs& o, const Vec2& duv, const ThetaFrame& frame) {
  const WorldNormal w = WorldNormalOf(o, frame);
  const double len = w.n.norm();
  if (NormalVanishes(w.pu, w.pv)) return Vec3::Constant(NAN);  // FragmentAt's limit normal
  const Vec3 N = w.n / len, dn = w.nu * duv.x() + w.nv * duv.y();
  const Vec3 slope = (dn - N * N.dot(dn)) / len;
  return slope.allFinite() ? slope : Vec3::Constant(NAN);
}

double TurnRate(const TableResidual& g, const Vec2& gradY) {
  const double len = gradY.norm();
  if (!(g.along > 0.0) || !(len > 0.0)) return NAN;  // the normal is across the scan plane
  return -g.grad.dot(Vec2(-gradY.y(), gradY.x())) / (len * g.along);
}

}  // namespace patchscan

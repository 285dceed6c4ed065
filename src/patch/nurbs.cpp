#include "patch/nurbs.h"

#include "core/shortest_number.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace patchscan {

void Bernstein(int n, double t, double* b, double* db, double* ddb) {
  // Degree m from degree m - 1 in place, B(k,m) = (1-t) B(k,m-1) + t B(k-1,m-1), keeping
  // degrees n - 1 and n - 2 for the derivatives: B'(k,n) = n (B(k-1,n-1) - B(k,n-1)).
  double lower1[kMaxNurbsOrder] = {}, lower2[kMaxNurbsOrder] = {};
  b[0] = 1.0;
  for (int m = 0; m <= n; ++m) {
    if (m > 0) {
      b[m] = 0.0;
      for (int k = m; k >= 0; --k) b[k] = (1.0 - t) * b[k] + (k > 0 ? t * b[k - 1] : 0.0);
    }
    if (m == n - 2) std::copy(b, b + m + 1, lower2);
    if (m == n - 1) std::copy(b, b + m + 1, lower1);
  }
  auto at = [](const double* d, int size, int k) { return k >= 0 && k < size ? d[k] : 0.0; };
  for (int k = 0; k <= n; ++k) {
    db[k] = n >= 1 ? n * (at(lower1, n, k - 1) - at(lower1, n, k)) : 0.0;
    ddb[k] = n >= 2 ? n * (n - 1) * (at(lower2, n - 1, k - 2) - 2.0 * at(lower2, n - 1, k - 1) + at(lower2, n - 1, k))
                    : 0.0;
  }
}

NurbsPiece::NurbsPiece(int uDegree, int vDegree, std::vector<Vec4> pw, double u0, double u1, double v0, double v1)
    : p_(uDegree), q_(vDegree), pw_(std::move(pw)), u0_(u0), u1_(u1), v0_(v0), v1_(v1) {
  hull_.reserve(pw_.size());
  for (const Vec4& h : pw_) hull_.push_back(h.head<3>() / h.w());
}

std::string NurbsPiece::Describe() const {
  std::ostringstream s;
  s << "NURBS piece, degree " << p_ << "x" << q_ << ", u [" << u0_ << ", " << u1_ << "] v [" << v0_ << ", " << v1_
    << "]";
  return s.str();
}

void NurbsPiece::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const bool first = Wants(order, DerivOrder::First);
  const bool second = Wants(order, DerivOrder::Second);
  double bu[kMaxNurbsOrder], dbu[kMaxNurbsOrder], ddbu[kMaxNurbsOrder];
  double bv[kMaxNurbsOrder], dbv[kMaxNurbsOrder], ddbv[kMaxNurbsOrder];
  Bernstein(p_, u, bu, dbu, ddbu);
  Bernstein(q_, v, bv, dbv, ddbv);
  // The homogeneous point H = (A, w) and its derivatives: v collapsed row by row, then u.
  Vec4 h = Vec4::Zero(), hu = Vec4::Zero(), hv = Vec4::Zero(), huu = Vec4::Zero(), huv = Vec4::Zero(),
       hvv = Vec4::Zero();
  const int rowLength = p_ + 1;
  for (int i = 0; i <= p_; ++i) {
    Vec4 c = Vec4::Zero(), cv = Vec4::Zero(), cvv = Vec4::Zero();
    for (int j = 0; j <= q_; ++j) {
      const Vec4& pt = pw_[static_cast<std::size_t>(j * rowLength + i)];
      c += bv[j] * pt;
      if (first) cv += dbv[j] * pt;
      if (second) cvv += ddbv[j] * pt;
    }
    h += bu[i] * c;
    if (first) {
      hu += dbu[i] * c;
      hv += bu[i] * cv;
    }
    if (second) {
      huu += ddbu[i] * c;
      huv += dbu[i] * cv;
      hvv += bu[i] * cvv;
    }
  }
  // The quotient rule: P = A / w, so A = w P and A' = w' P + w P'.
  const double w = h.w();
  const Vec3 p = h.head<3>() / w;
  out->p = p;
  if (!first) return;
  const Vec3 pu = (hu.head<3>() - hu.w() * p) / w;
  const Vec3 pv = (hv.head<3>() - hv.w() * p) / w;
  out->dpdu = pu;
  out->dpdv = pv;
  if (!second) return;
  out->d2pdu2 = (huu.head<3>() - 2.0 * hu.w() * pu - huu.w() * p) / w;
  out->d2pduv = (huv.head<3>() - hu.w() * pv - hv.w() * pu - huv.w() * p) / w;
  out->d2pdv2 = (hvv.head<3>() - 2.0 * hv.w() * pv - hvv.w() * p) / w;
}

namespace {

// Control points in rows of `n` (the direction being split), `m` rows.
struct Grid {
  int n, m;
  std::vector<Vec4> pts;  // index i + n * j
};

// Inserts knot t once (Boehm): the curve is unchanged, one control point more in each row.
void InsertKnot(Grid* g, std::vector<double>* knots, int degree, double t) {
  const auto& k = *knots;
  // The span holding t, k[s] < t <= k[s + 1] (so that the domain's end is inside one),
  // or at the domain's start k[s] <= t < k[s + 1].
  int s = static_cast<int>(std::lower_bound(k.begin(), k.end(), t) - k.begin()) - 1;
  if (s < degree) s = static_cast<int>(std::upper_bound(k.begin(), k.end(), t) - k.begin()) - 1;
  if (s < degree || s >= g->n) throw std::logic_error("knot insertion outside the curve's domain");
  Grid out{g->n + 1, g->m, std::vector<Vec4>(static_cast<std::size_t>((g->n + 1) * g->m))};
  for (int j = 0; j < g->m; ++j) {
    const Vec4* in = &g->pts[static_cast<std::size_t>(j * g->n)];
    Vec4* o = &out.pts[static_cast<std::size_t>(j * out.n)];
    for (int i = 0; i <= out.n - 1; ++i) {
      if (i <= s - degree) {
        o[i] = in[i];
      } else if (i <= s) {
        const double a = (t - k[static_cast<std::size_t>(i)]) / (k[static_cast<std::size_t>(i + degree)] - k[static_cast<std::size_t>(i)]);
        o[i] = (1.0 - a) * in[i - 1] + a * in[i];
      } else {
        o[i] = in[i - 1];
      }
    }
  }
  knots->insert(knots->begin() + s + 1, t);
  *g = std::move(out);
}

// Raises every knot value in [lo, hi] (and lo and hi themselves) to multiplicity `degree`
// at least: each span of [lo, hi] is then a Bézier curve of its degree + 1 control points.
void SplitAtKnots(Grid* g, std::vector<double>* knots, int degree, double lo, double hi) {
  std::vector<double> values{lo, hi};
  for (double t : *knots)
    if (t > lo && t < hi) values.push_back(t);
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  for (double t : values) {
    const auto count = std::count(knots->begin(), knots->end(), t);
    for (auto c = count; c < degree; ++c) InsertKnot(g, knots, degree, t);
  }
}

Grid Transposed(const Grid& g) {
  Grid t{g.m, g.n, std::vector<Vec4>(g.pts.size())};
  for (int j = 0; j < g.m; ++j)
    for (int i = 0; i < g.n; ++i) t.pts[static_cast<std::size_t>(i * g.m + j)] = g.pts[static_cast<std::size_t>(j * g.n + i)];
  return t;
}

std::string Str(double x) { return ShortestNumber(x); }

void CheckDirection(const char* dir, int n, int order, const std::vector<double>& knot, double* lo, double* hi) {
  const std::string d = dir;
  if (order < 2 || order > kMaxNurbsOrder)
    throw std::invalid_argument(d + "order " + std::to_string(order) + " is not from 2 to " +
                                std::to_string(kMaxNurbsOrder));
  if (n < order)
    throw std::invalid_argument("n" + d + " " + std::to_string(n) + " control points are fewer than the " + d +
                                "order " + std::to_string(order));
  if (knot.size() != static_cast<std::size_t>(n + order))
    throw std::invalid_argument(d + "knot has " + std::to_string(knot.size()) + " values, n" + d + " + " + d +
                                "order = " + std::to_string(n + order));
  for (std::size_t k = 0; k < knot.size(); ++k) {
    if (!std::isfinite(knot[k])) throw std::invalid_argument(d + "knot value " + std::to_string(k) + " is not finite");
    if (k > 0 && knot[k] < knot[k - 1])
      throw std::invalid_argument(d + "knot decreases at value " + std::to_string(k) + " (" + Str(knot[k - 1]) +
                                  " then " + Str(knot[k]) + ")");
  }
  // The curve is defined on [knot[order-1], knot[n]]: a range reaching past it by rounding
  // is clamped to it.
  const double a = knot[static_cast<std::size_t>(order - 1)], b = knot[static_cast<std::size_t>(n)];
  if (!std::isfinite(*lo) || !std::isfinite(*hi) || !(*lo < *hi))
    throw std::invalid_argument(d + "min " + Str(*lo) + " and " + d + "max " + Str(*hi) + " are not a range");
  const double slack = 1e-6 * std::max(1.0, b - a);
  if (*lo < a - slack || *hi > b + slack || !(a < b))
    throw std::invalid_argument(d + "range [" + Str(*lo) + ", " + Str(*hi) + "] is not within the knots' [" + Str(a) +
                                ", " + Str(b) + "]");
  *lo = std::max(*lo, a);
  *hi = std::min(*hi, b);
  if (!(*lo < *hi)) throw std::invalid_argument(d + "range is empty");
}

// The spans [k[s], k[s+1]] of `knots` with k[s] < k[s+1] inside [lo, hi]: (first control
// point of the span's Bézier piece, its start, its end).
struct Span {
  int first;
  double start, end;
};
std::vector<Span> Spans(const std::vector<double>& knots, int degree, double lo, double hi) {
  std::vector<Span> out;
  for (int s = degree; s + 1 < static_cast<int>(knots.size()); ++s) {
    const double a = knots[static_cast<std::size_t>(s)], b = knots[static_cast<std::size_t>(s + 1)];
    if (a < b && a >= lo && b <= hi) out.push_back({s - degree, a, b});
  }
  return out;
}

}  // namespace

std::vector<std::vector<Vec4>> SplitNurbsCurve(int order, const std::vector<double>& knot, double tmin, double tmax,
                                               const std::vector<Vec4>& points) {
  CheckDirection("", static_cast<int>(points.size()), order, knot, &tmin, &tmax);
  Grid g{static_cast<int>(points.size()), 1, {}};
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Vec4& h = points[k];
    if (!h.allFinite()) throw std::invalid_argument("control point " + std::to_string(k) + " is not finite");
    if (!(h.w() > 0.0))
      throw std::invalid_argument("control point " + std::to_string(k) + " has weight " + Str(h.w()) +
                                  " (weights are positive)");
    g.pts.push_back(h);
  }
  const int p = order - 1;
  std::vector<double> k = knot;
  SplitAtKnots(&g, &k, p, tmin, tmax);
  std::vector<std::vector<Vec4>> segments;
  for (const Span& s : Spans(k, p, tmin, tmax))
    segments.emplace_back(g.pts.begin() + s.first, g.pts.begin() + s.first + p + 1);
  return segments;
}

std::vector<std::vector<Vec3>> SplitNurbsCurve(int order, const std::vector<double>& knot, double tmin, double tmax,
                                               const std::vector<Vec3>& points) {
  std::vector<Vec4> h;
  h.reserve(points.size());
  for (const Vec3& p : points) h.emplace_back(p.x(), p.y(), 0.0, p.z());
  std::vector<std::vector<Vec3>> segments;
  for (const auto& seg : SplitNurbsCurve(order, knot, tmin, tmax, h)) {
    segments.emplace_back();
    for (const Vec4& q : seg) segments.back().emplace_back(q.x(), q.y(), q.w());
  }
  return segments;
}

std::vector<NurbsPiece> SplitNurbs(const NurbsSurface& in) {
  double umin = in.umin, umax = in.umax, vmin = in.vmin, vmax = in.vmax;
  CheckDirection("u", in.nu, in.uorder, in.uknot, &umin, &umax);
  CheckDirection("v", in.nv, in.vorder, in.vknot, &vmin, &vmax);
  if (in.pw.size() != static_cast<std::size_t>(in.nu) * static_cast<std::size_t>(in.nv))
    throw std::invalid_argument(std::to_string(in.pw.size()) + " control points, nu x nv = " +
                                std::to_string(in.nu * in.nv));
  for (std::size_t k = 0; k < in.pw.size(); ++k) {
    if (!in.pw[k].allFinite()) throw std::invalid_argument("control point " + std::to_string(k) + " is not finite");
    if (!(in.pw[k].w() > 0.0))
      throw std::invalid_argument("control point " + std::to_string(k) + " has weight " + Str(in.pw[k].w()) +
                                  " (weights are positive)");
  }
  const int p = in.uorder - 1, q = in.vorder - 1;
  // Along u, row by row; then along v, on the transposed grid.
  Grid g{in.nu, in.nv, in.pw};
  std::vector<double> uk = in.uknot, vk = in.vknot;
  SplitAtKnots(&g, &uk, p, umin, umax);
  g = Transposed(g);
  SplitAtKnots(&g, &vk, q, vmin, vmax);
  g = Transposed(g);  // u fastest again: g.n points along u, g.m along v
  std::vector<NurbsPiece> pieces;
  for (const Span& sv : Spans(vk, q, vmin, vmax))
    for (const Span& su : Spans(uk, p, umin, umax)) {
      std::vector<Vec4> pts;
      pts.reserve(static_cast<std::size_t>((p + 1) * (q + 1)));
      for (int j = 0; j <= q; ++j)
        for (int i = 0; i <= p; ++i) pts.push_back(g.pts[static_cast<std::size_t>((sv.first + j) * g.n + su.first + i)]);
      pieces.emplace_back(p, q, std::move(pts), su.start, su.end, sv.start, sv.end);
    }
  return pieces;
}

}  // namespace patchscan

namespace patchscan {

NurbsSurface RepeatPeriods(const NurbsSurface& in, bool alongU, double lo, double hi, double closeTol) {
  // Work along u: a v direction is the transposed surface's u.
  NurbsSurface s = in;
  if (!alongU) {
    std::swap(s.nu, s.nv), std::swap(s.uorder, s.vorder), std::swap(s.uknot, s.vknot);
    std::swap(s.umin, s.vmin), std::swap(s.umax, s.vmax);
    for (int j = 0; j < in.nv; ++j)
      for (int i = 0; i < in.nu; ++i)
        s.pw[static_cast<std::size_t>(i * in.nv + j)] = in.pw[static_cast<std::size_t>(j * in.nu + i)];
  }
  const int p = s.uorder - 1, n = s.nu;
  const auto& k = s.uknot;
  if (p < 1 || n < 2 || k.size() != static_cast<std::size_t>(n + p + 1)) throw std::invalid_argument("not a NURBS surface");
  const double d0 = k[static_cast<std::size_t>(p)], d1 = k[static_cast<std::size_t>(n)], period = d1 - d0;
  if (!(period > 0.0) || k.front() != d0 || k.back() != d1)
    throw std::invalid_argument("its knots are not clamped at the ends of its domain");
  for (int j = 0; j < s.nv; ++j) {
    const Vec4& a = s.pw[static_cast<std::size_t>(j * n)];
    const Vec4& b = s.pw[static_cast<std::size_t>(j * n + n - 1)];
    if ((a - b).norm() > closeTol) throw std::invalid_argument("it is not closed along the direction it is repeated in");
  }
  const double first = std::floor((lo - d0) / period), last = std::ceil((hi - d0) / period);
  const int copies = static_cast<int>(std::max(1.0, last - first));
  if (copies > 64) throw std::invalid_argument("its range spans more than 64 periods");
  const double shift0 = first * period;
  NurbsSurface out = s;
  out.nu = copies * (n - 1) + 1;
  out.uknot.assign(static_cast<std::size_t>(p + 1), d0 + shift0);
  for (int c = 0; c < copies; ++c) {
    const double shift = shift0 + c * period;
    for (int i = p + 1; i < n; ++i) out.uknot.push_back(k[static_cast<std::size_t>(i)] + shift);
    for (int r = 0; r < (c + 1 < copies ? p : p + 1); ++r) out.uknot.push_back(d1 + shift);
  }
  out.pw.clear();
  for (int j = 0; j < s.nv; ++j)
    for (int c = 0; c < copies; ++c)
      for (int i = c == 0 ? 0 : 1; i < n; ++i) out.pw.push_back(s.pw[static_cast<std::size_t>(j * n + i)]);
  out.umin = std::max(lo, out.uknot.front()), out.umax = std::min(hi, out.uknot.back());
  if (alongU) return out;
  NurbsSurface t = out;
  std::swap(t.nu, t.nv), std::swap(t.uorder, t.vorder), std::swap(t.uknot, t.vknot);
  std::swap(t.umin, t.vmin), std::swap(t.umax, t.vmax);
  for (int j = 0; j < out.nv; ++j)
    for (int i = 0; i < out.nu; ++i)
      t.pw[static_cast<std::size_t>(i * out.nv + j)] = out.pw[static_cast<std::size_t>(j * out.nu + i)];
  return t;
}

}  // namespace patchscan

#include "patch/polygon.h"

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>

namespace patchscan {
namespace {

double Cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Whether p lies in the counter-clockwise triangle abc or on its boundary.
bool InTriangle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& p) {
  return Cross(a, b, p) >= 0.0 && Cross(b, c, p) >= 0.0 && Cross(c, a, p) >= 0.0;
}

double SignedArea(const std::vector<Vec2>& q, std::span<const std::uint32_t> loop) {
  double a = 0.0;
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec2& p = q[loop[k]];
    const Vec2& n = q[loop[(k + 1) % loop.size()]];
    a += p.x() * n.y() - n.x() * p.y();
  }
  return 0.5 * a;
}

// Joins a clockwise hole to the counter-clockwise polygon `poly` (indices into q) by a
// bridge from the hole's rightmost point M to a point of the polygon it sees: the nearest
// crossing of the ray from M towards +x with an edge, or the reflex point inside the
// triangle of M, that crossing and the edge's right end that makes the least angle with
// the ray (Eberly, "Triangulation by Ear Clipping", §3). False if the ray meets no edge
// (a hole outside the outline).
bool Bridge(const std::vector<Vec2>& q, std::vector<std::uint32_t>& poly, const std::vector<std::uint32_t>& hole) {
  std::size_t m = 0;
  for (std::size_t k = 1; k < hole.size(); ++k)
    if (q[hole[k]].x() > q[hole[m]].x()) m = k;
  const Vec2 M = q[hole[m]];
  const std::size_t n = poly.size();
  double bestX = INFINITY;
  std::size_t visible = n;  // index in poly of the point the bridge goes to
  Vec2 hit = Vec2::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2& a = q[poly[k]];
    const Vec2& b = q[poly[(k + 1) % n]];
    // Edges to the right of M rise in a counter-clockwise polygon.
    if (!(a.y() <= M.y() && M.y() <= b.y()) || a.y() == b.y()) continue;
    const double x = a.x() + (M.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
    if (x < M.x() || x >= bestX) continue;
    bestX = x;
    hit = Vec2(x, M.y());
    if (x == a.x() && M.y() == a.y()) visible = k;
    else if (x == b.x() && M.y() == b.y()) visible = (k + 1) % n;
    else visible = a.x() > b.x() ? k : (k + 1) % n;
  }
  if (visible == n) return false;
  const Vec2 P = q[poly[visible]];
  if (P != hit) {
    // A reflex point of the polygon inside triangle M, hit, P hides P from M: take the
    // one nearest the ray's direction instead.
    double bestCos = -2.0, bestDist = INFINITY;
    const bool ccw = Cross(M, hit, P) > 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2& r = q[poly[k]];
      if (k == visible || r == P) continue;
      const bool reflex = Cross(q[poly[(k + n - 1) % n]], r, q[poly[(k + 1) % n]]) <= 0.0;
      if (!reflex || !(ccw ? InTriangle(M, hit, P, r) : InTriangle(M, P, hit, r))) continue;
      const Vec2 d = r - M;
      const double dist = d.norm();
      const double c = dist > 0.0 ? d.x() / dist : 1.0;
      if (c > bestCos || (c == bestCos && dist < bestDist)) {
        bestCos = c;
        bestDist = dist;
        visible = k;
      }
    }
  }
  std::vector<std::uint32_t> joined;
  joined.reserve(n + hole.size() + 2);
  joined.insert(joined.end(), poly.begin(), poly.begin() + static_cast<std::ptrdiff_t>(visible) + 1);
  for (std::size_t k = 0; k <= hole.size(); ++k) joined.push_back(hole[(m + k) % hole.size()]);
  joined.push_back(poly[visible]);
  joined.insert(joined.end(), poly.begin() + static_cast<std::ptrdiff_t>(visible) + 1, poly.end());
  poly.swap(joined);
  return true;
}

// Clips ears off the counter-clockwise polygon `poly` (indices into q; bridges repeat
// points) until three points are left.
std::size_t ClipEars(const std::vector<Vec2>& q, std::vector<std::uint32_t> poly,
                     std::vector<std::array<std::uint32_t, 3>>* out) {
  std::size_t made = 0;
  std::size_t n = poly.size();
  std::vector<std::size_t> prev(n), next(n);
  for (std::size_t k = 0; k < n; ++k) {
    prev[k] = (k + n - 1) % n;
    next[k] = (k + 1) % n;
  }
  auto isEar = [&](std::size_t k) {
    const Vec2 &a = q[poly[prev[k]]], &b = q[poly[k]], &c = q[poly[next[k]]];
    if (Cross(a, b, c) <= 0.0) return false;
    for (std::size_t j = next[next[k]]; j != prev[k]; j = next[j]) {
      const Vec2& p = q[poly[j]];
      if (p == a || p == b || p == c) continue;  // a bridge's repeated point
      if (InTriangle(a, b, c, p)) return false;
    }
    return true;
  };
  std::size_t k = 0, misses = 0;
  while (n > 3) {
    const Vec2 &a = q[poly[prev[k]]], &b = q[poly[k]], &c = q[poly[next[k]]];
    const double turn = Cross(a, b, c);
    // A point where the outline goes straight on, or back on itself, bounds no area.
    const bool flat = turn == 0.0;
    // With no ear in a whole turn (a self-intersecting outline) the point is clipped anyway.
    const bool clip = flat || isEar(k) || misses > n;
    if (!clip) {
      k = next[k];
      ++misses;
      continue;
    }
    if (!flat && turn > 0.0) {
      out->push_back({poly[prev[k]], poly[k], poly[next[k]]});
      ++made;
    }
    next[prev[k]] = next[k];
    prev[next[k]] = prev[k];
    k = prev[k];
    --n;
    misses = 0;
  }
  const std::size_t a = prev[k], c = next[k];
  if (Cross(q[poly[a]], q[poly[k]], q[poly[c]]) > 0.0) {
    out->push_back({poly[a], poly[k], poly[c]});
    ++made;
  }
  return made;
}

}  // namespace

Vec3 NewellNormal(std::span<const Vec3> points, std::span<const std::uint32_t> loop) {
  Vec3 n = Vec3::Zero();
  if (loop.empty()) return n;
  // About the first point, so that a polygon far from the origin loses no digits.
  const Vec3 o = points[loop[0]];
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec3 p = points[loop[k]] - o;
    const Vec3 q = points[loop[(k + 1) % loop.size()]] - o;
    n += p.cross(q);
  }
  return 0.5 * n;
}

std::size_t TriangulatePolygon(std::span<const Vec3> points, std::span<const std::vector<std::uint32_t>> loops,
                               std::vector<std::array<std::uint32_t, 3>>* out) {
  if (loops.empty() || loops[0].size() < 3) return 0;
  const Vec3 normal = NewellNormal(points, loops[0]);
  int axis = 0;
  normal.cwiseAbs().maxCoeff(&axis);
  if (!(std::abs(normal[axis]) > 0.0)) return 0;
  // The plane's coordinates: the other two axes, in the order that makes the outline
  // counter-clockwise.
  int i = (axis + 1) % 3, j = (axis + 2) % 3;
  if (normal[axis] < 0.0) std::swap(i, j);
  std::vector<Vec2> q(points.size(), Vec2::Zero());
  for (const auto& loop : loops)
    for (const std::uint32_t k : loop) q[k] = Vec2(points[k][i], points[k][j]);

  std::vector<std::uint32_t> poly = loops[0];
  // A convex outline without holes is a fan.
  if (loops.size() == 1) {
    bool convex = true;
    for (std::size_t k = 0; k < poly.size() && convex; ++k)
      convex = Cross(q[poly[k]], q[poly[(k + 1) % poly.size()]], q[poly[(k + 2) % poly.size()]]) >= 0.0;
    if (convex) {
      std::size_t made = 0;
      for (std::size_t k = 1; k + 1 < poly.size(); ++k)
        if (Cross(q[poly[0]], q[poly[k]], q[poly[k + 1]]) > 0.0) {
          out->push_back({poly[0], poly[k], poly[k + 1]});
          ++made;
        }
      return made;
    }
  }
  std::vector<std::vector<std::uint32_t>> holes;
  for (std::size_t h = 1; h < loops.size(); ++h) {
    if (loops[h].size() < 3) continue;
    holes.push_back(loops[h]);
    if (SignedArea(q, holes.back()) > 0.0) std::reverse(holes.back().begin(), holes.back().end());
  }
  auto rightmost = [&](const std::vector<std::uint32_t>& loop) {
    double x = -INFINITY;
    for (const std::uint32_t k : loop) x = std::max(x, q[k].x());
    return x;
  };
  std::stable_sort(holes.begin(), holes.end(),
                   [&](const auto& a, const auto& b) { return rightmost(a) > rightmost(b); });
  for (const auto& hole : holes) Bridge(q, poly, hole);
  return ClipEars(q, std::move(poly), out);
}

}  // namespace patchscan

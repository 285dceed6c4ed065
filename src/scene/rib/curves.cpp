// The RIB Curves request (RenderMan Interface 3.2, "Curves"): linear and cubic curves in
// the current v basis, periodic or not, with "width" or "constantwidth", each segment a
// CurveRibbon facing the camera (patch/curves.h).
#include <Eigen/LU>
#include <cmath>
#include <string>

#include "patch/curves.h"
#include "scene/rib/parser.h"
#include "scene/text_file.h"

namespace patchscan::rib {
namespace {

// The Bézier points of the cubic [t^3 t^2 t 1] M G.
std::array<Vec3, 4> CubicToBezier(const Mat4& m, const std::array<Vec3, 4>& g) {
  Vec3 a[4];  // a[k]: the coefficient of t^(3 - k)
  for (int k = 0; k < 4; ++k) a[k] = m(k, 0) * g[0] + m(k, 1) * g[1] + m(k, 2) * g[2] + m(k, 3) * g[3];
  const Vec3 &c3 = a[0], &c2 = a[1], &c1 = a[2], &c0 = a[3];
  return {c0, c0 + c1 / 3.0, c0 + (2.0 * c1 + c2) / 3.0, c0 + c1 + c2 + c3};
}

// The same for a scalar: the values at t = 0 and t = 1.
std::pair<double, double> CubicEnds(const Mat4& m, const double g[4]) {
  double end0 = 0.0, end1 = 0.0;
  for (int j = 0; j < 4; ++j) {
    end0 += m(3, j) * g[j];
    end1 += (m(0, j) + m(1, j) + m(2, j) + m(3, j)) * g[j];
  }
  return {end0, end1};
}

}  // namespace

bool RibParser::Curves(const Request& r) {
  // Curves type nvertices wrap paramlist.
  if (!InWorld(r)) return false;
  if (r.args.size() < 3 || !r.args[0].Textual() || r.args[0].strings.size() != 1 || !r.args[2].Textual() ||
      r.args[2].strings.size() != 1)
    return Fail(r.line, "Curves expects a type, the vertex counts and a wrap, then its parameters");
  const std::string& type = r.args[0].strings[0];
  const std::string& wrap = r.args[2].strings[0];
  if (type != "linear" && type != "cubic") return Fail(r.args[0].line, "Curves: type is \"linear\" or \"cubic\", not " + Shown(type));
  if (wrap != "periodic" && wrap != "nonperiodic")
    return Fail(r.args[2].line, "Curves: wrap is \"periodic\" or \"nonperiodic\", not " + Shown(wrap));
  const bool cubic = type == "cubic", periodic = wrap == "periodic";
  std::vector<std::size_t> nverts;
  if (!Counts(r, 1, "vertex counts", 1, kMaxPolygonCount, &nverts)) return false;
  const Basis& basis = attr_.vBasis;
  const std::size_t step = static_cast<std::size_t>(basis.step);
  // Segments and varying values per curve (RenderMan Interface 3.2, "Curves").
  std::vector<std::size_t> segments, varyingOf;
  std::size_t points = 0, varying = 0;
  for (std::size_t c = 0; c < nverts.size(); ++c) {
    const std::size_t n = nverts[c];
    std::size_t segs = 0;
    if (cubic && !periodic) {
      if (n < 4 || (n - 4) % step != 0)
        return Fail(r.args[1].line, "Curves: a nonperiodic cubic curve has 4 + " + std::to_string(step) +
                                        " k vertices in this basis, curve " + std::to_string(c + 1) + " has " +
                                        std::to_string(n));
      segs = (n - 4) / step + 1;
    } else if (cubic) {
      if (n < 4 || n % step != 0)
        return Fail(r.args[1].line, "Curves: a periodic cubic curve has a multiple of " + std::to_string(step) +
                                        " vertices (4 at least) in this basis, curve " + std::to_string(c + 1) +
                                        " has " + std::to_string(n));
      segs = n / step;
    } else {
      if (n < 2) return Fail(r.args[1].line, "Curves: a linear curve has 2 vertices at least, curve " + std::to_string(c + 1) + " has 1");
      segs = periodic ? n : n - 1;
    }
    segments.push_back(segs);
    varyingOf.push_back(varying);
    points += n;
    varying += cubic ? (periodic ? segs : segs + 1) : n;
  }

  std::vector<Param> params;
  if (!Params(r, 3, &params)) return false;
  const Value* p = nullptr;
  const Value* pw = nullptr;
  const Value* width = nullptr;
  std::string widthDeclared;
  double constantWidth = 1.0;  // RenderMan's default width
  for (const Param& q : params) {
    if (q.name == "P") p = q.value;
    else if (q.name == "Pw") pw = q.value;
    else if (q.name == "width") {
      if (!q.value->Numeric()) return Fail(q.value->line, "Curves: \"width\" expects numbers");
      width = q.value;
      widthDeclared = q.declared;
    } else if (q.name == "constantwidth") {
      if (!ParamNumbers(r, q, 1, &constantWidth)) return false;
    } else if (q.name == "N") {
      Warn(q.value->line, "Curves/N", "Curves: \"N\" is ignored: curves are drawn as ribbons facing the camera");
    } else {
      IgnoreParam(r, q);
    }
  }
  if (p && pw) return Fail(pw->line, "Curves: both \"P\" and \"Pw\": give one");
  if (!p && !pw) return Fail(r.line, "Curves: no \"P\"");
  const Value* given = p ? p : pw;
  const std::size_t dims = p ? 3 : 4;
  if (!given->Numeric() || given->numbers.size() != dims * points)
    return Fail(given->line, std::string("Curves: ") + (p ? "\"P\"" : "\"Pw\"") + " expects " + std::to_string(dims * points) +
                                 " numbers (" + std::to_string(points) + " points), found " + std::to_string(given->Size()));
  // Widths: per varying value, per vertex, per curve or one; as declared, else by count.
  enum class Per { Varying, Vertex, Curve, One } per = Per::One;
  if (width) {
    const std::size_t n = width->numbers.size();
    const bool vertex = widthDeclared.find("vertex") != std::string::npos;
    const bool uniform = widthDeclared.find("uniform") != std::string::npos;
    if (vertex && n == points) per = Per::Vertex;
    else if (uniform && n == nverts.size()) per = Per::Curve;
    else if (!vertex && !uniform && n == varying) per = Per::Varying;
    else if (!vertex && !uniform && n == points) per = Per::Vertex;
    else if (!vertex && n == nverts.size()) per = Per::Curve;
    else if (!vertex && !uniform && n == 1) per = Per::One;
    else
      return Fail(width->line, "Curves: \"width\" expects " + std::to_string(varying) + " values (varying), " +
                                   std::to_string(points) + " (vertex), " + std::to_string(nverts.size()) +
                                   " (uniform) or 1, found " + std::to_string(n));
    for (const double w : width->numbers)
      if (!(w >= 0.0)) return Fail(width->line, "Curves: widths are not negative");
  }
  if (!(constantWidth >= 0.0)) return Fail(r.line, "Curves: \"constantwidth\" is not negative");

  // World space: ribbons face the camera there. A width scales with the transformation's
  // mean stretch (the cube root of its volume scale).
  const Mat3 linear = attr_.transform.block<3, 3>(0, 0);
  const double stretch = std::cbrt(std::abs(linear.determinant()));
  std::vector<Vec3> world(points);
  for (std::size_t k = 0; k < points; ++k) {
    const double* x = given->numbers.data() + dims * k;
    const double w = p ? 1.0 : x[3];
    if (!(w > 0.0)) return Fail(given->line, "Curves: \"Pw\" weights must be positive");
    world[k] = (attr_.transform * Vec4(x[0] / w, x[1] / w, x[2] / w, 1.0)).head<3>();
  }
  const Mat4 saved = attr_.transform;
  attr_.transform = Mat4::Identity();
  std::size_t first = 0;
  for (std::size_t c = 0; c < nverts.size(); ++c) {
    const std::size_t n = nverts[c];
    for (std::size_t s = 0; s < segments[c]; ++s) {
      std::array<Vec3, 4> bezier;
      double w0 = constantWidth, w1 = constantWidth;
      if (cubic) {
        std::array<Vec3, 4> g;
        double gw[4] = {0, 0, 0, 0};
        for (std::size_t k = 0; k < 4; ++k) {
          const std::size_t at = first + (s * step + k) % n;
          g[k] = world[at];
          if (per == Per::Vertex) gw[k] = width->numbers[at];
        }
        bezier = CubicToBezier(basis.m, g);
        if (per == Per::Vertex) std::tie(w0, w1) = CubicEnds(basis.m, gw);
      } else {
        const Vec3 a = world[first + s], b = world[first + (s + 1) % n];
        bezier = {a, a + (b - a) / 3.0, a + 2.0 * (b - a) / 3.0, b};
        if (per == Per::Vertex) {
          w0 = width->numbers[first + s];
          w1 = width->numbers[first + (s + 1) % n];
        }
      }
      if (per == Per::Varying) {
        const std::size_t nv = cubic ? (periodic ? segments[c] : segments[c] + 1) : n;
        w0 = width->numbers[varyingOf[c] + s % nv];
        w1 = width->numbers[varyingOf[c] + (s + 1) % nv];
      } else if (per == Per::Curve) {
        w0 = w1 = width->numbers[c];
      } else if (per == Per::One && width) {
        w0 = w1 = width->numbers[0];
      }
      CurveRibbon ribbon(bezier, std::max(0.0, w0) * stretch, std::max(0.0, w1) * stretch);
      // Each segment begins exactly where the one before ends (a periodic curve's first
      // where its last ends): shared edges are the same points, so no crack between them.
      if (s > 0) ribbon.JoinAfter(std::get<CurveRibbon>(scene_.surfaces.back().shape));
      AddSurface(r, std::move(ribbon));
    }
    if (periodic) {
      auto& firstRibbon = std::get<CurveRibbon>(scene_.surfaces[scene_.surfaces.size() - segments[c]].shape);
      firstRibbon.JoinAfter(std::get<CurveRibbon>(scene_.surfaces.back().shape));
    }
    first += n;
  }
  attr_.transform = saved;
  return true;
}

}  // namespace patchscan::rib

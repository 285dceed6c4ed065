// The RIB geometry requests: bases, patches, patch meshes, quadrics and Geometry "teapot".
#include "scene/bpt_reader.h"
#include "scene/rib/parser.h"
#include "scene/rib/reader.h"
#include "scene/text_file.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <stdexcept>

namespace patchscan::rib {

bool RibParser::InWorld(const Request& r) {
  if (!sawWorldOpen()) return Fail(r.line, r.name + " outside WorldBegin/WorldEnd");
  return true;
}

void RibParser::AddSurface(const Request& r, Shape shape, std::shared_ptr<const PieceTrim> trim) {
  Surface s{std::move(shape), Affine3(attr_.transform), std::move(trim)};
  scene_.surfaces.push_back(std::move(s));
  scene_.sourceLines.push_back(r.line);
  scene_.sourceFiles.push_back(file_);
  scene_.appearanceOf.push_back(AppearanceIndex());
}

std::uint32_t RibParser::AppearanceIndex() {
  Appearance a = attr_.appearance;
  // RenderMan Interface 3.2, "Orientation": the normal is flipped where the orientation
  // differs from the handedness of the current coordinate system (left-handed unless
  // the camera and object transformations together mirror it).
  const bool mirrored = (cameraFromWorld_ * attr_.transform).block<3, 3>(0, 0).determinant() < 0.0;
  a.reversed = attr_.insideOrientation != mirrored;
  // Distinct appearances, found by hash: a scene may give each of its surfaces its own.
  std::vector<std::uint32_t>& same = appearanceIndex_[HashOf(a)];
  for (const std::uint32_t k : same)
    if (scene_.appearances[k] == a) return k;
  same.push_back(static_cast<std::uint32_t>(scene_.appearances.size()));
  scene_.appearances.push_back(a);
  return same.back();
}

std::size_t RibParser::HashOf(const Appearance& a) {
  std::size_t h = std::hash<std::string>()(a.textureName) ^ (std::hash<std::string>()(a.bumpName) << 2) ^
                  (std::hash<std::string>()(a.environmentName) << 3) ^
                  (static_cast<std::size_t>(a.shader) << 1) ^
                  (static_cast<std::size_t>(a.twoSided) << 5) ^ (static_cast<std::size_t>(a.reversed) << 6);
  for (const double x : {a.colour.x(), a.colour.y(), a.colour.z(), a.opacity.x(), a.opacity.y(), a.opacity.z(), a.ka,
                         a.kd, a.ks, a.roughness, a.specularColour.x(), a.specularColour.y(), a.specularColour.z(), a.bumpScale, a.kr})
    h = h * 1000003u ^ std::hash<double>()(x);
  return h;
}

bool RibParser::BasisRequest(const Request& r) {
  // Basis ubasis ustep vbasis vstep: each basis a name or 16 numbers.
  if (r.args.size() != 4) return Fail(r.line, "Basis expects 4 arguments (ubasis ustep vbasis vstep), found " + std::to_string(r.args.size()));
  Basis b[2];
  for (int k = 0; k < 2; ++k) {
    const Value& basis = r.args[2 * k];
    const Value& step = r.args[2 * k + 1];
    if (basis.Textual()) {
      const auto named = basis.strings.size() == 1 ? BasisByName(basis.strings[0]) : std::nullopt;
      if (!named)
        return Fail(basis.line, "Basis: unknown basis " + Shown(basis.strings.empty() ? "" : basis.strings[0]) +
                                    " (known: bezier, b-spline, catmull-rom, hermite, power)");
      b[k] = *named;
    } else {
      if (basis.numbers.size() != 16) return Fail(basis.line, "Basis: a basis matrix has 16 numbers, found " + std::to_string(basis.numbers.size()));
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) b[k].m(i, j) = basis.numbers[4 * i + j];
      b[k].name = "matrix";
    }
    if (step.kind != Value::Kind::Number || step.numbers[0] != std::floor(step.numbers[0]) ||
        step.numbers[0] < 1 || step.numbers[0] > 4)
      return Fail(step.line, "Basis: a step is a whole number from 1 to 4");
    b[k].step = static_cast<int>(step.numbers[0]);
  }
  attr_.uBasis = b[0];
  attr_.vBasis = b[1];
  return true;
}

bool RibParser::Points(const Request& r, size_t first, size_t count, bool rationalAllowed, int nu, int nv,
                       std::initializer_list<std::string_view> readElsewhere) {
  std::vector<Param> params;
  if (!Params(r, first, &params)) return false;
  const Value* p = nullptr;
  const Value* pw = nullptr;
  const Value* pz = nullptr;
  for (const Param& q : params) {
    if (q.name == "P") p = q.value;
    else if (q.name == "Pw" && rationalAllowed) pw = q.value;
    else if (q.name == "Pw") return Fail(q.value->line, r.name + ": \"Pw\" (rational points) is not supported here; give \"P\"");
    else if (q.name == "Pz" && nu > 0) pz = q.value;
    else if (q.name == "Pz") return Fail(q.value->line, r.name + ": \"Pz\" (height fields) is for Patch and PatchMesh; give \"P\"");
    else if (std::find(readElsewhere.begin(), readElsewhere.end(), q.name) == readElsewhere.end()) IgnoreParam(r, q);
  }
  if ((p != nullptr) + (pw != nullptr) + (pz != nullptr) > 1)
    return Fail((pz ? pz : pw)->line, r.name + ": more than one of \"P\", \"Pw\" and \"Pz\": give one");
  if (pz) {
    // A height field (RenderMan Interface 3.2, "Geometric Primitives"): each point's x and
    // y are the mesh's surface parameters there, on a grid of nu x nv from 0 to 1.
    if (!pz->Numeric() || pz->numbers.size() != count)
      return Fail(pz->line, r.name + ": \"Pz\" expects " + std::to_string(count) + " numbers (" + std::to_string(count) +
                                " points), found " + std::to_string(pz->Size()));
    pts_.resize(count);
    hpts_.resize(count);
    rational_ = false;
    for (size_t k = 0; k < count; ++k) {
      const auto i = static_cast<int>(k % static_cast<size_t>(nu)), j = static_cast<int>(k / static_cast<size_t>(nu));
      pts_[k] = Vec3(nu > 1 ? double(i) / (nu - 1) : 0.0, nv > 1 ? double(j) / (nv - 1) : 0.0, pz->numbers[k]);
      hpts_[k] = pts_[k].homogeneous();
    }
    return true;
  }
  if (!p && !pw) return Fail(r.line, r.name + (rationalAllowed ? ": no \"P\" or \"Pw\"" : ": no \"P\""));
  const Value* given = p ? p : pw;
  const size_t dims = p ? 3 : 4;
  if (!given->Numeric() || given->numbers.size() != dims * count)
    return Fail(given->line, r.name + (p ? ": \"P\" expects " : ": \"Pw\" expects ") + std::to_string(dims * count) +
                                 " numbers (" + std::to_string(count) + " points), found " + std::to_string(given->Size()));
  pts_.resize(count);
  hpts_.resize(count);
  rational_ = false;
  const double* n = given->numbers.data();
  for (size_t k = 0; k < count; ++k) {
    const Vec4 h = p ? Vec4(n[3 * k], n[3 * k + 1], n[3 * k + 2], 1.0) : Vec4(n[4 * k], n[4 * k + 1], n[4 * k + 2], n[4 * k + 3]);
    // Homogeneous points (RenderMan Interface 3.2, "Pw": (w x, w y, w z, w)) with a
    // positive weight: the surface then lies in the hull of the points divided by it.
    if (!(h.w() > 0.0) || !std::isfinite(h.w()))
      return Fail(given->line, r.name + ": point " + std::to_string(k) + " of \"Pw\" has weight " +
                                   ShortestNumber(h.w()) + " (weights are positive)");
    hpts_[k] = h;
    pts_[k] = h.head<3>() / h.w();
    rational_ = rational_ || h.w() != 1.0;
  }
  return true;
}

bool RibParser::PatchType(const Request& r, bool* bicubic) {
  std::string type;
  if (!StringArg(r, 0, &type)) return false;
  if (type != "bilinear" && type != "bicubic")
    return Fail(r.line, r.name + ": unknown type " + Shown(type) + " (known: \"bilinear\", \"bicubic\")");
  *bicubic = type == "bicubic";
  return true;
}

bool RibParser::Patch(const Request& r) {
  bool bicubic = false;
  if (!InWorld(r) || !PatchType(r, &bicubic) || !Points(r, 1, bicubic ? 16 : 4, true, bicubic ? 4 : 2, bicubic ? 4 : 2))
    return false;
  if (rational_) {
    AddRationalPatch(r, hpts_, bicubic);
  } else if (bicubic) {
    std::array<Vec3, 16> cv;
    std::copy(pts_.begin(), pts_.end(), cv.begin());
    AddSurface(r, BicubicPatch(cv, attr_.uBasis, attr_.vBasis));
  } else {
    AddSurface(r, BilinearPatch({pts_[0], pts_[1], pts_[2], pts_[3]}));
  }
  return true;
}

void RibParser::AddRationalPatch(const Request& r, std::vector<Vec4> cv, bool bicubic) {
  // A rational patch is a rational Bézier patch: its homogeneous points in the Bézier basis,
  // a NuPatch piece of degree 3 (or 1) on [0,1]^2.
  if (bicubic) {
    std::array<Vec4, 16> given;
    std::copy(cv.begin(), cv.end(), given.begin());
    const std::array<Vec4, 16> b = BezierHomogeneous(given, attr_.uBasis, attr_.vBasis);
    cv.assign(b.begin(), b.end());
  }
  const int degree = bicubic ? 3 : 1;
  AddSurface(r, NurbsPiece(degree, degree, std::move(cv), 0.0, 1.0, 0.0, 1.0));
}

bool RibParser::MeshCount(const Request& r, int n, bool periodic, bool bicubic, int step, const char* dir, int* count) {
  if (!bicubic) {
    if (n < (periodic ? 1 : 2)) return Fail(r.line, std::string("PatchMesh: too few points in ") + dir);
    *count = periodic ? n : n - 1;
    return true;
  }
  if (periodic) {
    if (n < 4 || n % step != 0) return Fail(r.line, std::string("PatchMesh: a periodic bicubic mesh needs a multiple of the ") + dir + " step (" + std::to_string(step) + ") of at least 4 points in " + dir + ", found " + std::to_string(n));
    *count = n / step;
  } else {
    if (n < 4 || (n - 4) % step != 0) return Fail(r.line, std::string("PatchMesh: a nonperiodic bicubic mesh needs 4 + k * ") + std::to_string(step) + " points in " + dir + ", found " + std::to_string(n));
    *count = (n - 4) / step + 1;
  }
  return true;
}

bool RibParser::PatchMesh(const Request& r) {
  bool bicubic = false;
  if (!InWorld(r) || !PatchType(r, &bicubic)) return false;
  if (r.args.size() < 5) return Fail(r.line, "PatchMesh expects type nu uwrap nv vwrap, then \"P\"");
  int n[2];
  bool periodic[2];
  for (int k = 0; k < 2; ++k) {
    const Value& count = r.args[1 + 2 * k];
    const Value& wrap = r.args[2 + 2 * k];
    if (count.kind != Value::Kind::Number || count.numbers[0] != std::floor(count.numbers[0]) || count.numbers[0] < 1 || count.numbers[0] > 1e7)
      return Fail(count.line, "PatchMesh: a point count is a whole number from 1 to 10000000");
    if (wrap.kind != Value::Kind::String || (wrap.strings[0] != "periodic" && wrap.strings[0] != "nonperiodic"))
      return Fail(wrap.line, "PatchMesh: wrap is \"periodic\" or \"nonperiodic\"");
    n[k] = static_cast<int>(count.numbers[0]);
    periodic[k] = wrap.strings[0] == "periodic";
  }
  const int nu = n[0], nv = n[1];
  if (static_cast<long long>(nu) * nv > 10'000'000LL) return Fail(r.line, "PatchMesh: more than 10000000 points");
  if (!Points(r, 5, static_cast<size_t>(nu) * nv, true, nu, nv)) return false;
  const int uStep = bicubic ? attr_.uBasis.step : 1, vStep = bicubic ? attr_.vBasis.step : 1;
  int nuPatches = 0, nvPatches = 0;
  if (!MeshCount(r, nu, periodic[0], bicubic, uStep, "u", &nuPatches) ||
      !MeshCount(r, nv, periodic[1], bicubic, vStep, "v", &nvPatches))
    return false;
  const int order = bicubic ? 4 : 2;
  scene_.ReserveSurfaces(static_cast<std::size_t>(nuPatches) * static_cast<std::size_t>(nvPatches), true);
  for (int pv = 0; pv < nvPatches; ++pv)
    for (int pu = 0; pu < nuPatches; ++pu) {
      std::array<Vec3, 16> cv;
      std::vector<Vec4> hcv(static_cast<size_t>(order * order));
      for (int j = 0; j < order; ++j)
        for (int i = 0; i < order; ++i) {
          const int iu = (pu * uStep + i) % nu, iv = (pv * vStep + j) % nv;
          cv[static_cast<size_t>(order * j + i)] = pts_[static_cast<size_t>(iv) * nu + iu];
          hcv[static_cast<size_t>(order * j + i)] = hpts_[static_cast<size_t>(iv) * nu + iu];
        }
      if (rational_) AddRationalPatch(r, std::move(hcv), bicubic);
      else if (bicubic) AddSurface(r, BicubicPatch(cv, attr_.uBasis, attr_.vBasis));
      else AddSurface(r, BilinearPatch({cv[0], cv[1], cv[2], cv[3]}));
    }
  return true;
}

bool RibParser::NuPatch(const Request& r) {
  // NuPatch nu uorder uknot umin umax nv vorder vknot vmin vmax, then "P" or "Pw"
  // (RenderMan Interface 3.2, "Non-uniform Rational B-spline Patches").
  if (!InWorld(r)) return false;
  if (r.args.size() < 10 || r.args[2].kind == Value::Kind::String)
    return Fail(r.line, "NuPatch expects nu uorder uknot umin umax nv vorder vknot vmin vmax, then \"P\" or \"Pw\"");
  NurbsSurface n;
  for (int k = 0; k < 2; ++k) {
    const char* dir = k == 0 ? "u" : "v";
    const Value* a = &r.args[static_cast<size_t>(5 * k)];
    auto number = [&](const Value& v, const std::string& what, double* out) {
      if (!v.Numeric() || v.numbers.size() != 1) return Fail(v.line, "NuPatch: " + what + " is one number");
      *out = v.numbers[0];
      return true;
    };
    double count = 0, order = 0;
    double* range = k == 0 ? &n.umin : &n.vmin;
    double* rangeEnd = k == 0 ? &n.umax : &n.vmax;
    if (!number(a[0], std::string("n") + dir, &count) || !number(a[1], std::string(dir) + "order", &order) ||
        !number(a[3], std::string(dir) + "min", range) || !number(a[4], std::string(dir) + "max", rangeEnd))
      return false;
    const auto nCount = WholeIn(count, 1, 10'000'000);
    const auto nOrder = WholeIn(order, 1, 1000);
    if (!nCount) return Fail(a[0].line, std::string("NuPatch: n") + dir + " is a whole number from 1 to 10000000");
    if (!nOrder) return Fail(a[1].line, std::string("NuPatch: ") + dir + "order is a whole number from 1");
    if (!a[2].Numeric()) return Fail(a[2].line, std::string("NuPatch: ") + dir + "knot is an array of numbers");
    (k == 0 ? n.nu : n.nv) = *nCount;
    (k == 0 ? n.uorder : n.vorder) = *nOrder;
    (k == 0 ? n.uknot : n.vknot) = a[2].numbers;
  }
  if (static_cast<long long>(n.nu) * n.nv > 10'000'000LL) return Fail(r.line, "NuPatch: more than 10000000 points");
  if (!Points(r, 10, static_cast<size_t>(n.nu) * static_cast<size_t>(n.nv))) return false;
  n.pw = hpts_;
  std::vector<NurbsPiece> pieces;
  try {
    pieces = SplitNurbs(n);
  } catch (const std::invalid_argument& e) {
    return Fail(r.line, std::string("NuPatch: ") + e.what());
  }
  if (attr_.trim) {
    auto trim = attr_.trim;
    if (trim->KeepsInside() != attr_.trimKeepsInside) trim = std::make_shared<const TrimLoops>(trim->WithSense(attr_.trimKeepsInside));
    std::vector<TrimmedPiece> kept = TrimPieces(trim, std::move(pieces));
    scene_.ReserveSurfaces(kept.size(), true);
    for (TrimmedPiece& k : kept) AddSurface(r, std::move(k.piece), std::move(k.trim));
    return true;
  }
  scene_.ReserveSurfaces(pieces.size(), true);
  for (NurbsPiece& piece : pieces) AddSurface(r, std::move(piece));
  return true;
}

bool RibParser::TrimCurve(const Request& r) {
  // TrimCurve [ncurves] [order] [knot] [min] [max] [n] [u] [v] [w]: nloops is the length
  // of ncurves; curves are NURBS in homogeneous (u, v, w), concatenated.
  const char* names[] = {"ncurves", "order", "knot", "min", "max", "n", "u", "v", "w"};
  if (r.args.size() != 9) return Fail(r.line, "TrimCurve expects 9 arrays: ncurves order knot min max n u v w");
  for (std::size_t k = 0; k < 9; ++k)
    if (!r.args[k].Numeric()) return Fail(r.args[k].line, std::string("TrimCurve: ") + names[k] + " is an array of numbers");
  const auto& ncurves = r.args[0].numbers;
  const auto& order = r.args[1].numbers;
  const auto& knot = r.args[2].numbers;
  const auto& tmin = r.args[3].numbers;
  const auto& tmax = r.args[4].numbers;
  const auto& n = r.args[5].numbers;
  const auto& u = r.args[6].numbers;
  const auto& v = r.args[7].numbers;
  const auto& w = r.args[8].numbers;
  std::size_t curves = 0;
  for (double c : ncurves) {
    const auto k = WholeIn(c, 1, 10'000'000);
    if (!k) return Fail(r.args[0].line, "TrimCurve: ncurves are whole numbers from 1");
    curves += static_cast<std::size_t>(*k);
  }
  if (ncurves.empty()) return Fail(r.args[0].line, "TrimCurve: ncurves is empty (no loops)");
  for (const std::size_t k : {1, 3, 4, 5})
    if (r.args[k].numbers.size() != curves)
      return Fail(r.args[k].line, std::string("TrimCurve: ") + names[k] + " has " + std::to_string(r.args[k].numbers.size()) +
                                      " values for " + std::to_string(curves) + " curves");
  std::size_t points = 0, knots = 0;
  std::vector<int> orders, counts;
  for (std::size_t c = 0; c < curves; ++c) {
    const auto o = WholeIn(order[c], 1, 1000), m = WholeIn(n[c], 1, 10'000'000);
    if (!o) return Fail(r.args[1].line, "TrimCurve: order " + std::to_string(c + 1) + " is not a whole number from 1");
    if (!m) return Fail(r.args[5].line, "TrimCurve: n " + std::to_string(c + 1) + " is not a whole number from 1");
    orders.push_back(*o);
    counts.push_back(*m);
    points += static_cast<std::size_t>(*m);
    knots += static_cast<std::size_t>(*m + *o);
    if (points > 10'000'000) return Fail(r.line, "TrimCurve: more than 10000000 points");
  }
  if (knot.size() != knots)
    return Fail(r.args[2].line, "TrimCurve: knot has " + std::to_string(knot.size()) + " values, the curves' n + order add up to " +
                                    std::to_string(knots));
  for (std::size_t k = 6; k < 9; ++k)
    if (r.args[k].numbers.size() != points)
      return Fail(r.args[k].line, std::string("TrimCurve: ") + names[k] + " has " + std::to_string(r.args[k].numbers.size()) +
                                      " values, the curves' n add up to " + std::to_string(points));
  std::vector<std::vector<TrimCurveInput>> loops;
  std::size_t c = 0, kk = 0, pp = 0;
  for (double nc : ncurves) {
    loops.emplace_back();
    for (int j = 0; j < static_cast<int>(nc); ++j, ++c) {
      TrimCurveInput in;
      in.order = orders[c];
      in.knot.assign(knot.begin() + static_cast<std::ptrdiff_t>(kk), knot.begin() + static_cast<std::ptrdiff_t>(kk + static_cast<std::size_t>(counts[c] + orders[c])));
      kk += static_cast<std::size_t>(counts[c] + orders[c]);
      in.tmin = tmin[c];
      in.tmax = tmax[c];
      for (int i = 0; i < counts[c]; ++i, ++pp) in.uvw.emplace_back(u[pp], v[pp], w[pp]);
      loops.back().push_back(std::move(in));
    }
  }
  try {
    attr_.trim = std::make_shared<const TrimLoops>(loops, attr_.trimKeepsInside);
  } catch (const std::invalid_argument& e) {
    return Fail(r.line, std::string("TrimCurve: ") + e.what());
  }
  return true;
}

bool RibParser::AttributeRequest(const Request& r) {
  std::string name;
  std::vector<Param> params;
  if (!NameAndParams(r, &name, &params)) return false;
  if (name == "displacementbound") {
    // The bound a displacement may move the surface by: a bump never moves it, so no bound
    // widens; its values are checked all the same.
    for (const Param& p : params) {
      if (p.name == "coordinatesystem") continue;  // the space of "sphere": any is valid
      if (p.name != "sphere") {
        IgnoreParam(r, p);
        continue;
      }
      double sphere = 0.0;
      if (!ParamNumbers(r, p, 1, &sphere)) return false;
      if (!(sphere >= 0.0)) return Fail(p.value->line, "Attribute \"displacementbound\" \"sphere\" must be 0 or more");
    }
    return true;
  }
  if (name != "trimcurve") {
    Warn(r.line, "Attribute " + name, "Attribute " + Shown(name) + " is not supported here: skipped");
    return true;
  }
  for (const Param& p : params) {
    if (p.name != "sense") {
      IgnoreParam(r, p);
      continue;
    }
    std::string sense;
    if (!ParamString(r, p, &sense)) return false;
    if (sense != "inside" && sense != "outside")
      return Fail(p.value->line, "Attribute \"trimcurve\" \"sense\" is \"inside\" or \"outside\", not " + Shown(sense));
    attr_.trimKeepsInside = sense == "inside";
  }
  return true;
}

bool RibParser::Quadric(const Request& r) {
  if (!InWorld(r)) return false;
  const std::string& n = r.name;
  const size_t count = n == "Hyperboloid" ? 7 : n == "Torus" ? 5 : (n == "Cone" || n == "Disk") ? 3 : 4;
  size_t used = 0;
  if (!Numbers(r, count, &used)) return false;
  std::vector<Param> params;
  if (!Params(r, used, &params)) return false;
  for (const Param& p : params) IgnoreParam(r, p);
  const double* a = num_.data();
  const double thetaMax = a[count - 1];
  // Sweeps are angles of at most a turn either way (RenderMan Interface 3.2, "Quadrics").
  if (!(std::abs(thetaMax) <= 360.0)) return Fail(r.line, n + ": thetamax must be from -360 to 360 degrees");
  if (n == "Torus" && !(std::abs(a[2]) <= 360.0 && std::abs(a[3]) <= 360.0))
    return Fail(r.line, "Torus: phimin and phimax must be from -360 to 360 degrees");
  auto positive = [&](double x, const char* what) {
    return x > 0 ? true : Fail(r.line, n + ": " + what + " must be positive");
  };
  if (n == "Sphere") {
    if (!positive(a[0], "the radius")) return false;
    AddSurface(r, Sphere(a[0], a[1], a[2], thetaMax));
  } else if (n == "Cylinder") {
    if (!positive(a[0], "the radius")) return false;
    AddSurface(r, Cylinder(a[0], a[1], a[2], thetaMax));
  } else if (n == "Cone") {
    if (!positive(a[1], "the radius")) return false;
    AddSurface(r, Cone(a[0], a[1], thetaMax));
  } else if (n == "Paraboloid") {
    if (!positive(a[0], "rmax") || !positive(a[2] - a[1], "zmax - zmin")) return false;
    AddSurface(r, Paraboloid(a[0], a[1], a[2], thetaMax));
  } else if (n == "Hyperboloid") {
    AddSurface(r, Hyperboloid(Vec3(a[0], a[1], a[2]), Vec3(a[3], a[4], a[5]), thetaMax));
  } else if (n == "Disk") {
    if (!positive(a[1], "the radius")) return false;
    AddSurface(r, Disk(a[0], a[1], thetaMax));
  } else {
    if (!positive(a[0], "the major radius") || !positive(a[1], "the minor radius")) return false;
    AddSurface(r, Torus(a[0], a[1], a[2], a[3], thetaMax));
  }
  return true;
}

bool RibParser::Geometry(const Request& r) {
  std::string name;
  if (!InWorld(r) || !StringArg(r, 0, &name)) return false;
  if (name != "teapot") {
    Warn(r.line, "geometry " + name, "Geometry: unknown geometry " + Shown(name) + ": skipped");
    return true;
  }
  // Parsed once per program: a scene may hold a thousand teapots.
  static const auto teapot = ParseBpt(TeapotBptText(), "teapot");
  if (auto* e = std::get_if<SourceError>(&teapot)) return Fail(r.line, "Geometry \"teapot\": " + e->What());
  for (const BptPatch& p : std::get<BptFile>(teapot).patches) AddSurface(r, BicubicPatch(p.cv));
  return true;
}

}  // namespace patchscan::rib

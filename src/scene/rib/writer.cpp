#include "scene/rib/writer.h"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <set>
#include <sstream>
#include <type_traits>

namespace patchscan {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
// The far clipping plane written: RenderMan's infinity.
constexpr double kFarClip = 1e30;

void Point(std::ostream& out, const Vec3& p) { out << ' ' << p.x() << ' ' << p.y() << ' ' << p.z(); }

// RIB's row-vector form of a column-vector affine matrix: its transpose, row by row.
void Matrix(std::ostream& out, const Mat4& m) {
  out << '[';
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out << (i + j == 0 ? "" : " ") << m(j, i);
  out << ']';
}

// The RIB request of a quadric, its arguments as it was given them, or of a curve segment
// (Bézier basis, its two widths), to 17 significant digits: read back, the same doubles.
// "" for the shapes written otherwise.
const char* QuadricName(const Sphere&) { return "Sphere"; }
const char* QuadricName(const Cylinder&) { return "Cylinder"; }
const char* QuadricName(const Cone&) { return "Cone"; }
const char* QuadricName(const Paraboloid&) { return "Paraboloid"; }
const char* QuadricName(const Hyperboloid&) { return "Hyperboloid"; }
const char* QuadricName(const Disk&) { return "Disk"; }
const char* QuadricName(const Torus&) { return "Torus"; }
template <class Shape>
std::string ShapeRequest(const Shape& shape) {
  std::ostringstream s;
  s.precision(17);
  if constexpr (requires { QuadricName(shape); }) {
    s << QuadricName(shape);
    for (const double x : shape.Given()) s << ' ' << x;
  } else if constexpr (std::is_same_v<Shape, CurveRibbon>) {
    s << "Basis \"bezier\" 3 \"bezier\" 3\nCurves \"cubic\" [4] \"nonperiodic\" \"P\" [";
    for (const Vec3& p : shape.Bezier()) s << ' ' << p.x() << ' ' << p.y() << ' ' << p.z();
    s << " ] \"width\" [" << shape.Width0() << ' ' << shape.Width1() << ']';
  }
  return s.str();
}

// A NURBS piece as the NuPatch of one Bézier span (clamped knots at the ends of the span
// it came from, each of multiplicity order), its points homogeneous: read back, it is the
// same piece. A trimmed piece is written in its own attribute block after the sense and
// every trim loop of its NuPatch, each segment a curve of one Bézier span, in the
// NuPatch's (u,v): read back, the loops are the same segments.
void NuPatch(std::ostream& out, const NurbsPiece& n, const PieceTrim* trim) {
  if (trim) {
    const TrimLoops& loops = *trim->loops;
    out << "AttributeBegin\nAttribute \"trimcurve\" \"sense\" \"" << (loops.KeepsInside() ? "inside" : "outside")
        << "\"\nTrimCurve [";
    for (int l = 0; l < loops.Loops(); ++l) out << (l ? " " : "") << loops.LoopBegin(l + 1) - loops.LoopBegin(l);
    const auto& segs = loops.Segments();
    auto each = [&](auto&& item) {
      out << " [";
      for (std::size_t k = 0; k < segs.size(); ++k) {
        if (k) out << ' ';
        item(segs[k]);
      }
      out << ']';
    };
    out << ']';
    each([&](const TrimSegment& g) { out << g.Degree() + 1; });
    each([&](const TrimSegment& g) {
      for (int i = 0; i < 2 * (g.Degree() + 1); ++i) out << (i ? " " : "") << (i <= g.Degree() ? 0 : 1);
    });
    each([&](const TrimSegment&) { out << 0; });
    each([&](const TrimSegment&) { out << 1; });
    each([&](const TrimSegment& g) { out << g.Degree() + 1; });
    for (int c = 0; c < 3; ++c)
      each([&](const TrimSegment& g) {
        for (std::size_t i = 0; i < g.Points().size(); ++i) out << (i ? " " : "") << g.Points()[i][c];
      });
    out << '\n';
  }
  out << "NuPatch";
  const double ends[2][2] = {{n.U0(), n.U1()}, {n.V0(), n.V1()}};
  for (int d = 0; d < 2; ++d) {
    const int degree = d == 0 ? n.UDegree() : n.VDegree();
    out << ' ' << degree + 1 << ' ' << degree + 1 << " [";
    for (int k = 0; k < 2 * (degree + 1); ++k) out << (k == 0 ? "" : " ") << ends[d][k <= degree ? 0 : 1];
    out << "] " << ends[d][0] << ' ' << ends[d][1];
  }
  out << " \"Pw\" [";
  for (const Vec4& h : n.Points()) out << ' ' << h.x() << ' ' << h.y() << ' ' << h.z() << ' ' << h.w();
  out << " ]\n";
  if (trim) out << "AttributeEnd\n";
}

void Triple(std::ostream& out, const Vec3& v) { out << '[' << v.x() << ' ' << v.y() << ' ' << v.z() << ']'; }

// The scene's lights in world space, as RenderMan's standard light shaders read them
// (colour as lightcolor at intensity 1; cone angles in radians).
void Lights(std::ostream& out, const std::vector<SceneLight>& lights) {
  int handle = 1;
  for (const SceneLight& l : lights) {
    using K = SceneLight::Kind;
    const bool shadows = !l.shadowNames.empty();
    const char* name = l.kind == K::Ambient   ? "ambientlight"
                       : l.kind == K::Distant ? (shadows ? "shadowdistant" : "distantlight")
                       : l.kind == K::Point   ? (shadows ? "shadowpoint" : "pointlight")
                                              : (shadows ? "shadowspot" : "spotlight");
    out << "LightSource \"" << name << "\" " << handle++ << " \"intensity\" [1] \"lightcolor\" ";
    Triple(out, l.colour);
    if (l.kind != K::Ambient) {
      out << " \"from\" ";
      Triple(out, l.from);
    }
    if (l.kind == K::Distant || l.kind == K::Spot) {
      out << " \"to\" ";
      Triple(out, l.to);
    }
    if (l.kind == K::Spot)
      out << " \"coneangle\" [" << l.coneAngle << "] \"conedeltaangle\" [" << l.coneDelta << "] \"beamdistribution\" ["
          << l.beamDistribution << ']';
    if (shadows) {
      // A point light's six maps by their faces' names, another light's one map.
      static const char* faces[] = {"sfpx", "sfnx", "sfpy", "sfny", "sfpz", "sfnz"};
      for (std::size_t k = 0; k < l.shadowNames.size() && k < 6; ++k)
        out << " \"" << (l.kind == K::Point ? faces[k] : "shadowname") << "\" [\"" << l.shadowNames[k] << "\"]";
      out << " \"bias\" [" << l.shadowBias << "] \"blur\" [" << l.shadowBlur << "] \"samples\" ["
          << l.shadowSamples * l.shadowSamples << ']';
    }
    out << '\n';
  }
}

// A surface's appearance as attributes: colour, opacity, sides, orientation and the
// standard shader with the parameters it reads.
void Attributes(std::ostream& out, const Appearance& a) {
  out << "Color ";
  Triple(out, a.colour);
  out << "\nOpacity ";
  Triple(out, a.opacity);
  out << "\nSides " << (a.twoSided ? 2 : 1) << '\n';
  if (a.reversed) out << "ReverseOrientation\n";
  if (!a.bumpName.empty())
    out << "Displacement \"bumpy\" \"amplitude\" [" << a.bumpScale << "] \"texturename\" \""
        << std::filesystem::absolute(a.bumpName).string() << "\"\n";
  using S = Appearance::Shader;
  switch (a.shader) {
    case S::Default: return;
    case S::Constant: out << "Surface \"constant\"\n"; return;
    case S::Matte: out << "Surface \"matte\" \"Ka\" [" << a.ka << "] \"Kd\" [" << a.kd << "]\n"; return;
    case S::Metal: out << "Surface \"metal\" \"Ka\" [" << a.ka << "] \"Ks\" [" << a.ks << "] \"roughness\" [" << a.roughness << "]\n"; return;
    case S::ShinyMetal:
      out << "Surface \"shinymetal\" \"Ka\" [" << a.ka << "] \"Ks\" [" << a.ks << "] \"Kr\" [" << a.kr << "] \"roughness\" ["
          << a.roughness << "]";
      if (!a.environmentName.empty()) out << " \"texturename\" \"" << std::filesystem::absolute(a.environmentName).string() << '"';
      out << '\n';
      return;
    case S::Plastic:
    case S::PaintedPlastic:
      out << "Surface \"" << (a.shader == S::Plastic ? "plastic" : "paintedplastic") << "\" \"Ka\" [" << a.ka << "] \"Kd\" ["
          << a.kd << "] \"Ks\" [" << a.ks << "] \"roughness\" [" << a.roughness << "] \"specularcolor\" ";
      Triple(out, a.specularColour);
      // The reader resolved the name against its scene file: absolute, it reads the same anywhere.
      if (a.shader == S::PaintedPlastic && !a.textureName.empty())
        out << " \"texturename\" \"" << std::filesystem::absolute(a.textureName).string() << '"';
      out << '\n';
      return;
  }
}

}  // namespace

namespace {

// A cage as RenderMan's SubdivisionMesh: scheme, face sizes and vertices, its tags (each
// crease chain a "crease" of one sharpness, corners one sharpness each, holes,
// interpolateboundary), "P".
void SubdivisionMesh(std::ostream& out, const SubdivMesh& m) {
  const char* scheme = m.scheme == SubdivScheme::Loop       ? "loop"
                       : m.scheme == SubdivScheme::Bilinear ? "bilinear"
                                                            : "catmull-clark";
  auto list = [&](const auto& values) {
    out << '[';
    for (std::size_t i = 0; i < values.size(); ++i) out << (i ? " " : "") << values[i];
    out << ']';
  };
  out << "SubdivisionMesh \"" << scheme << "\" ";
  list(m.faceSizes);
  out << "\n  ";
  list(m.faceVertices);
  std::vector<std::string> tags;
  std::vector<int> nargs, ints;
  std::vector<double> floats;
  for (const SubdivMesh::Crease& c : m.creases) {
    tags.push_back("\"crease\"");
    nargs.insert(nargs.end(), {static_cast<int>(c.chain.size()), 1});
    ints.insert(ints.end(), c.chain.begin(), c.chain.end());
    floats.push_back(c.sharpness);
  }
  if (!m.corners.empty()) {
    tags.push_back("\"corner\"");
    nargs.insert(nargs.end(), {static_cast<int>(m.corners.size()), static_cast<int>(m.corners.size())});
    for (const auto& [v, sharpness] : m.corners) ints.push_back(v);
    for (const auto& [v, sharpness] : m.corners) floats.push_back(sharpness);
  }
  if (!m.holes.empty()) {
    tags.push_back("\"hole\"");
    nargs.insert(nargs.end(), {static_cast<int>(m.holes.size()), 0});
    ints.insert(ints.end(), m.holes.begin(), m.holes.end());
  }
  tags.push_back("\"interpolateboundary\"");
  nargs.insert(nargs.end(), {1, 0});
  ints.push_back(m.interpolateBoundary);
  const bool faceVarying = !m.st.empty() && m.stClass == StClass::FaceVarying;
  if (faceVarying) {
    // RenderMan's numbers (scene/rib/subdiv.cpp); CornersPlus1 is its propagated corners.
    // CornersPlus2 (an .obj's 3) has no RenderMan form: written as CornersPlus1.
    const int rule = m.faceVaryingRule == FaceVaryingRule::All      ? 0
                     : m.faceVaryingRule == FaceVaryingRule::Smooth ? 2
                     : m.faceVaryingRule == FaceVaryingRule::Boundaries ? 3
                                                                        : 1;
    tags.push_back("\"facevaryinginterpolateboundary\"");
    nargs.insert(nargs.end(), {1, 0});
    ints.push_back(rule);
    if (m.faceVaryingRule == FaceVaryingRule::CornersPlus1 || m.faceVaryingRule == FaceVaryingRule::CornersPlus2) {
      tags.push_back("\"facevaryingpropagatecorners\"");
      nargs.insert(nargs.end(), {1, 0});
      ints.push_back(1);
    }
  }
  out << "\n  ";
  list(tags);
  out << ' ';
  list(nargs);
  out << ' ';
  list(ints);
  out << ' ';
  list(floats);
  out << "\n  \"P\" [";
  for (const Vec3& p : m.points) Point(out, p);
  out << " ]";
  if (!m.st.empty()) {
    // Face-varying values per face corner, in faceVertices' layout (a reader welds equal
    // values at a vertex, as RenderMan does); vertex and varying ones per point.
    out << "\n  \"" << (faceVarying ? "facevarying" : m.stClass == StClass::Vertex ? "vertex" : "varying") << " float[2] st\" [";
    auto value = [&](const Vec2& t) { out << ' ' << t.x() << ' ' << t.y(); };
    if (faceVarying) {
      for (const int k : m.stIndices) value(m.st[static_cast<std::size_t>(k)]);
    } else {
      for (const Vec2& t : m.st) value(t);
    }
    out << " ]";
  }
  out << "\n";
}

// A polygon mesh as PointsPolygons of its triangles in world space, with the vertices
// they use (renumbered in order) and their "N", "Cs" and "st" per point, so that it reads
// back as the same triangles with the same attributes.
void PolygonTriangles(std::ostream& out, const PolygonMesh& m) {
  std::vector<std::int64_t> number(m.vertices.size(), -1);
  std::vector<std::uint32_t> used;
  for (const auto& t : m.triangles)
    for (const std::uint32_t v : t)
      if (number[v] < 0) {
        number[v] = static_cast<std::int64_t>(used.size());
        used.push_back(v);
      }
  out << "PointsPolygons [";
  for (std::size_t k = 0; k < m.triangles.size(); ++k) out << (k ? " 3" : "3");
  out << "]\n  [";
  for (std::size_t k = 0; k < m.triangles.size(); ++k)
    for (int c = 0; c < 3; ++c) out << (k || c ? " " : "") << number[m.triangles[k][c]];
  out << "]\n  \"P\" [";
  for (const std::uint32_t v : used) Point(out, m.vertices[v].position);
  out << " ]\n  \"vertex normal N\" [";
  for (const std::uint32_t v : used) Point(out, m.vertices[v].normal);
  out << " ]\n  \"vertex color Cs\" [";
  for (const std::uint32_t v : used) Point(out, m.vertices[v].colour);
  out << " ]\n  \"vertex float[2] st\" [";
  for (const std::uint32_t v : used) out << ' ' << m.vertices[v].st.x() << ' ' << m.vertices[v].st.y();
  out << " ]\n";
}

}  // namespace

std::variant<std::string, RibWriteError> WriteRib(const Scene& scene, const Camera& camera,
                                                const RibWriteOptions& options) {
  std::ostringstream out;
  out << std::setprecision(17);
  out << "# RenderMan scene written by patchscan from " << scene.source << "\n";
  if (!options.displayName.empty()) out << "Display \"" << options.displayName << "\" \"file\" \"rgba\"\n";
  out << "Format " << camera.width << ' ' << camera.height << " 1\n"
      << "PixelSamples " << options.pixelSamples << ' ' << options.pixelSamples << "\n";
  // Step 1: the camera. RenderMan's field of view is that of the shorter side, and its
  // default screen window spans [-a, a] x [-1, 1] (a = width / height >= 1) or [-1, 1] x
  // [-1/a, 1/a] scaled by tan(fov / 2): equal to this camera's when fov is chosen so.
  Mat4 cameraFromWorld;
  double fovDeg = camera.fovDeg;
  const double aspect = static_cast<double>(camera.width) / camera.height;
  if (camera.cameraFromWorld && camera.orthographic) {
    cameraFromWorld = *camera.cameraFromWorld;
    const Vec4& w = camera.screenWindow;
    out << "Projection \"orthographic\"\nScreenWindow " << w[0] << ' ' << w[1] << ' ' << w[2] << ' ' << w[3] << '\n';
  } else if (camera.cameraFromWorld) {
    cameraFromWorld = *camera.cameraFromWorld;
    const Vec4& w = camera.screenWindow;
    const double t = std::min(std::abs(w[1] - w[0]), std::abs(w[3] - w[2])) / 2.0;
    fovDeg = 2.0 * std::atan(t) * kDegPerRad;
    out << "Projection \"perspective\" \"fov\" [" << fovDeg << "]\n"
        << "ScreenWindow " << w[0] / t << ' ' << w[1] / t << ' ' << w[2] / t << ' ' << w[3] / t << '\n';
  } else {
    // Camera space: x = right, y = up on the image, z = forward (left-handed).
    const Vec3 eye = EyePoint(camera), forward = ViewForward(camera), right = ViewRight(camera);
    const Vec3 up = right.cross(forward);  // a right-handed world's up, on the image
    cameraFromWorld = Mat4::Identity();
    cameraFromWorld.block<1, 3>(0, 0) = right.transpose();
    cameraFromWorld.block<1, 3>(1, 0) = up.transpose();
    cameraFromWorld.block<1, 3>(2, 0) = forward.transpose();
    cameraFromWorld.block<3, 1>(0, 3) = -cameraFromWorld.block<3, 3>(0, 0) * eye;
    const double tanHalf = std::tan(0.5 * camera.fovDeg / kDegPerRad);
    if (aspect < 1.0) fovDeg = 2.0 * std::atan(aspect * tanHalf) * kDegPerRad;
    out << "Projection \"perspective\" \"fov\" [" << fovDeg << "]\n";
  }
  out << "Clipping " << camera.hither << ' ' << kFarClip << "\nTransform ";
  Matrix(out, cameraFromWorld);
  out << "\nWorldBegin\n";
  // Step 2: the lights (none: the renderer's default rig, as in the source).
  Lights(out, scene.lights);
  // Step 3: the surfaces, each in its own attribute block when it is placed or has an
  // appearance of its own.
  std::set<const SubdivMesh*> cagesWritten;
  for (size_t k = 0; k < scene.surfaces.size(); ++k) {
    const Surface& s = scene.surfaces[k];
    // A cage's faces come from one request: the cage is written once, at its first face.
    const auto* face = std::get_if<SubdivFace>(&s.shape);
    if (face && !cagesWritten.insert(&face->Mesh()).second) continue;
    if (s.trim && !std::holds_alternative<NurbsPiece>(s.shape))
      return RibWriteError{"surface " + std::to_string(k + 1) + " (" + Describe(s) +
                           ") is trimmed: RenderMan trims NuPatches only"};
    const bool placed = !s.worldFromObject.matrix().isIdentity(0.0);
    const bool dressed = !scene.appearanceOf.empty();
    if (placed || dressed) out << "AttributeBegin\n";
    if (dressed) Attributes(out, scene.appearances[scene.appearanceOf[k]]);
    if (placed) {
      out << "ConcatTransform ";
      Matrix(out, s.worldFromObject.matrix());
      out << '\n';
    }
    const std::string quadric = std::visit([](const auto& shape) { return ShapeRequest(shape); }, s.shape);
    if (!quadric.empty()) {
      out << quadric << '\n';
    } else if (const auto* b = std::get_if<BicubicPatch>(&s.shape)) {
      out << "Patch \"bicubic\" \"P\" [";
      for (const Vec3& p : b->BezierPoints()) Point(out, p);
      out << " ]\n";
    } else if (const auto* l = std::get_if<BilinearPatch>(&s.shape)) {
      out << "Patch \"bilinear\" \"P\" [";
      for (const Vec3& p : l->Hull()) Point(out, p);
      out << " ]\n";
    } else if (const auto* n = std::get_if<NurbsPiece>(&s.shape)) {
      NuPatch(out, *n, s.trim.get());
    } else if (face) {
      SubdivisionMesh(out, face->Mesh());
    } else {
      return RibWriteError{"surface " + std::to_string(k + 1) + " (" + Describe(s) +
                           ") has no RIB form here: patches, NURBS, quadrics and subdivision meshes are written"};
    }
    if (placed || dressed) out << "AttributeEnd\n";
  }
  // Step 4: the polygons, in world space.
  for (std::size_t k = 0; k < scene.polygons.size(); ++k) {
    out << "AttributeBegin\n";
    if (!scene.appearanceOf.empty()) Attributes(out, scene.appearances[scene.appearanceOf[scene.surfaces.size() + k]]);
    PolygonTriangles(out, scene.polygons[k].mesh);
    out << "AttributeEnd\n";
  }
  out << "WorldEnd\n";
  return out.str();
}

}  // namespace patchscan

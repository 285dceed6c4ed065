#include "render/load.h"

#include <charconv>
#include <cmath>
#include <numbers>
#include <ostream>

#include "xscan/polygon_feed.h"

namespace patchscan::render {
namespace {

std::optional<double> ParseDouble(std::string_view t) {
  double v = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

std::optional<Vec3> ParseVec3(const std::string& text) {
  Vec3 v;
  std::string_view rest = text;
  for (int k = 0; k < 3; ++k) {
    const size_t comma = rest.find(',');
    if ((k < 2) != (comma != std::string_view::npos)) return std::nullopt;
    const auto x = ParseDouble(rest.substr(0, comma));
    if (!x) return std::nullopt;
    v[k] = *x;
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
  }
  return v;
}

std::optional<std::pair<int, int>> ParseSize(const std::string& text) {
  const size_t x = text.find('x');
  if (x == std::string::npos) return std::nullopt;
  int w = 0, h = 0;
  const char* b = text.data();
  const char* e = b + text.size();
  const auto [endW, ecW] = std::from_chars(b, b + x, w);
  const auto [endH, ecH] = std::from_chars(b + x + 1, e, h);
  if (ecW != std::errc() || ecH != std::errc() || endW != b + x || endH != e || w < 1 || h < 1)
    return std::nullopt;
  return std::make_pair(w, h);
}

namespace {

// The hither plane of a scene's camera without Clipping: 1/1000 of the camera-space
// depth of the scene's centre (its diagonal's length when the centre is not in front).
constexpr double kSceneHitherFraction = 1e-3;

// A RIB scene's camera (RenderMan Interface 3.2, "Camera"): the screen window defaults
// to [-a, a] x [-1, 1] for an image of aspect a >= 1 and [-1, 1] x [-1/a, 1/a] otherwise,
// and the perspective projection divides x and y by z tan(fov / 2).
std::variant<ResolvedCamera, std::string> SceneCamera(const CameraOptions& o, const Scene& scene,
                                                      Camera c) {
  ResolvedCamera r;
  const SceneImage& im = scene.image;
  c.cameraFromWorld = *im.cameraFromWorld;
  const double fov = o.fovDeg.value_or(im.fovDeg);
  if (!(fov >= kMinFovDeg && fov <= kMaxFovDeg))
    return "--fov: expected degrees from " + std::to_string(kMinFovDeg) + " to " + std::to_string(kMaxFovDeg);
  c.fovDeg = fov;
  const double aspect = static_cast<double>(c.width) / c.height;
  const Vec4 window = im.screenWindow ? *im.screenWindow
                      : aspect >= 1.0 ? Vec4(-aspect, aspect, -1, 1)
                                      : Vec4(-1, 1, -1 / aspect, 1 / aspect);
  // Orthographic: the window is on every plane of constant z, in camera-space units.
  c.orthographic = im.orthographic;
  c.screenWindow = im.orthographic ? window : Vec4(window * std::tan(0.5 * fov * std::numbers::pi / 180.0));
  if (im.hither) {
    c.hither = *im.hither;
  } else {
    const Bounds3 world = scene.WorldBounds();
    const Mat4& m = *c.cameraFromWorld;
    const Vec3 centre = world.Empty() ? Vec3::Zero() : world.Centre();
    const double z = (m * centre.homogeneous()).z();
    const double size = world.Empty() ? 1.0 : (m.block<3, 3>(0, 0) * world.Diagonal()).norm();
    c.hither = kSceneHitherFraction * (z > 0 ? z : std::max(size, 1e-300));
  }
  if (!o.hither.empty()) {
    const auto h = ParseDouble(o.hither);
    if (!h || !(*h > 0.0)) return "--hither: expected a positive distance, found '" + o.hither + "'";
    c.hither = *h;
  }
  if (auto why = ValidateCamera(c)) return "camera: " + *why;
  r.camera = c;
  return r;
}

}  // namespace

std::variant<ResolvedCamera, std::string> ResolveCamera(const CameraOptions& o,
                                                        const Scene& scene) {
  ResolvedCamera r;
  Camera& c = r.camera;
  c.width = scene.image.size ? scene.image.size->first : kDefaultWidth;
  c.height = scene.image.size ? scene.image.size->second : kDefaultHeight;
  if (!o.size.empty()) {
    const auto size = ParseSize(o.size);
    if (!size) return "--size: expected WIDTHxHEIGHT with positive whole numbers, found '" + o.size + "'";
    c.width = size->first;
    c.height = size->second;
  }
  if (scene.image.cameraFromWorld && o.eye.empty() && o.lookAt.empty() && o.up.empty())
    return SceneCamera(o, scene, c);
  c.fovDeg = o.fovDeg.value_or(kDefaultFovDeg);
  struct {
    const std::string& text;
    const char* name;
    Vec3* out;
  } vectors[] = {{o.eye, "--eye", &c.eye}, {o.lookAt, "--look-at", &c.lookAt}, {o.up, "--up", &c.up}};
  c.up = Vec3(0, 0, 1);
  for (auto& v : vectors) {
    if (v.text.empty()) continue;
    const auto parsed = ParseVec3(v.text);
    if (!parsed) return std::string(v.name) + ": expected three numbers X,Y,Z, found '" + v.text + "'";
    *v.out = *parsed;
  }
  // Validate what was given before framing uses it.
  if (c.up.norm() == 0.0) return "--up: the up vector must not be zero";
  if (!(c.fovDeg >= kMinFovDeg && c.fovDeg <= kMaxFovDeg))
    return "--fov: expected degrees from " + std::to_string(kMinFovDeg) + " to " +
           std::to_string(kMaxFovDeg);
  const Bounds3 world = scene.WorldBounds();
  if (o.eye.empty()) {
    // Frame the scene; a given look-at is kept as the direction's origin.
    Camera framed = FrameBounds(world, c, DefaultViewDirection(c.up));
    if (!o.lookAt.empty()) {
      framed.eye = c.lookAt + (framed.eye - framed.lookAt);
      framed.lookAt = c.lookAt;
    }
    c = framed;
    r.framed = true;
  } else {
    if (o.lookAt.empty()) c.lookAt = world.Empty() ? Vec3::Zero() : world.Centre();
    // The hither plane for a camera placed by hand: 1/1000 of the distance to look-at.
    constexpr double kHandHitherFraction = 1e-3;
    c.hither = kHandHitherFraction * (c.lookAt - c.eye).norm();
  }
  if (!o.hither.empty()) {
    const auto h = ParseDouble(o.hither);
    if (!h || !(*h > 0.0)) return "--hither: expected a positive distance, found '" + o.hither + "'";
    c.hither = *h;
  }
  if (auto why = ValidateCamera(c)) return "camera: " + *why;
  return r;
}

void Warn(const std::string& warning, std::ostream& log, std::set<std::string>* warned) {
  if (!warned || warned->insert(warning).second) log << "patchscan: warning: " << warning << '\n';
}

Result<LoadedScene> LoadSceneAndCamera(const std::string& file, const CameraOptions& opts, std::ostream& log,
                                       std::set<std::string>* warned) {
  LoadOptions lo;
  lo.frame = opts.frame;
  lo.objScheme = opts.objScheme;
  lo.cadAsNurbs = opts.cadAsNurbs;
  auto loaded = LoadScene(file, lo);
  if (auto* e = std::get_if<SourceError>(&loaded)) return Failure{Outcome::InputError, e->What()};
  auto resolved = ResolveCamera(opts, std::get<Scene>(loaded));
  if (auto* why = std::get_if<std::string>(&resolved)) return Failure{Outcome::BadOption, *why};
  for (const std::string& w : std::get<Scene>(loaded).warnings) Warn(w, log, warned);
  Scene& scene = std::get<Scene>(loaded);
  scene.FaceCamera(std::get<ResolvedCamera>(resolved).camera);
  return LoadedScene{std::move(scene), std::get<ResolvedCamera>(resolved)};
}

raster::RenderSettings SettingsFor(const Camera& camera, int aa) {
  raster::RenderSettings s;
  s.width = camera.width;
  s.height = camera.height;
  s.aa = aa;
  s.hither = camera.hither;
  s.eye = EyePoint(camera);
  s.orthographic = camera.orthographic;
  s.forward = ViewForward(camera);
  const Mat4 screen = ScreenFromWorld(camera);  // rows X, Y, depth, W
  s.screen << screen.row(0), screen.row(1), screen.row(3);
  const Vec3 right = ViewRight(camera);
  s.lights = raster::DefaultLightRig(s.forward, right.cross(s.forward), right);
  return s;
}

void AppendScenePolygons(const Scene& scene, const Camera& camera, raster::TriangleMesh* out) {
  for (std::size_t k = 0; k < scene.polygons.size(); ++k)
    AppendPolygonTriangles(scene.polygons[k].mesh, camera, static_cast<std::uint32_t>(scene.surfaces.size() + k), out);
}

raster::TriangleMesh PolygonTriangles(const Scene& scene, const Camera& camera) {
  raster::TriangleMesh mesh;
  AppendScenePolygons(scene, camera, &mesh);
  return mesh;
}

}  // namespace patchscan::render

#include "cli/camera_options.h"

#include <charconv>
#include <cmath>
#include <ostream>

#include "cli/exit_codes.h"

namespace patchscan::cli {
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

void AddCameraOptions(CLI::App* cmd, CameraOptions* o) {
  cmd->option_defaults()->group("Camera");
  cmd->add_option("--size", o->size, "image size in pixels, WIDTHxHEIGHT")
      ->capture_default_str();
  cmd->add_option("--eye", o->eye,
                  "eye position X,Y,Z in world space (default: framed automatically)");
  cmd->add_option("--look-at", o->lookAt,
                  "point X,Y,Z the camera looks at (default: the centre of the scene's bounds)");
  cmd->add_option("--up", o->up, "up direction X,Y,Z (default: 0,0,1, z up as in .bpt files)");
  cmd->add_option("--fov", o->fovDeg, "vertical field of view in degrees")->capture_default_str();
  cmd->add_option("--hither", o->hither,
                  "distance of the hither (near clipping) plane from the eye (default: half "
                  "the distance to the scene's bounding sphere when framed, else 1/1000 of "
                  "the distance to the look-at point)");
  cmd->option_defaults()->group("Options");
}

std::variant<ResolvedCamera, std::string> ResolveCamera(const CameraOptions& o,
                                                        const Scene& scene) {
  ResolvedCamera r;
  Camera& c = r.camera;
  const auto size = ParseSize(o.size);
  if (!size) return "--size: expected WIDTHxHEIGHT with positive whole numbers, found '" + o.size + "'";
  c.width = size->first;
  c.height = size->second;
  c.fovDeg = o.fovDeg;
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
  if (!(o.fovDeg >= kMinFovDeg && o.fovDeg <= kMaxFovDeg))
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

std::variant<LoadedScene, int> LoadSceneAndCamera(const std::string& file,
                                                  const CameraOptions& opts, std::ostream& err) {
  auto loaded = LoadScene(file);
  if (auto* e = std::get_if<SourceError>(&loaded)) {
    err << "patchscan: " << e->What() << '\n';
    return kExitInputError;
  }
  auto resolved = ResolveCamera(opts, std::get<Scene>(loaded));
  if (auto* why = std::get_if<std::string>(&resolved)) {
    err << "patchscan: " << *why << '\n';
    return kExitUsage;
  }
  return LoadedScene{std::move(std::get<Scene>(loaded)), std::get<ResolvedCamera>(resolved)};
}

}  // namespace patchscan::cli

#include "cli/render_setup.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <string>

#include "cli/exit_codes.h"

namespace patchscan::cli {
namespace {

// RenderMan light sources as the back end's lights: ambient lights sum into the rig's
// ambient light; the others keep their colour (intensity times lightcolor).
raster::LightRig SceneLights(const std::vector<SceneLight>& lights) {
  raster::LightRig rig;
  rig.ambient = raster::Rgb::Zero();
  for (const SceneLight& l : lights) {
    raster::Light out;
    out.intensity = l.colour;
    switch (l.kind) {
      case SceneLight::Kind::Ambient:
        rig.ambient += l.colour;
        continue;
      case SceneLight::Kind::Distant:
        out.kind = raster::Light::Kind::Directional;
        out.vector = (l.to - l.from).normalized();
        break;
      case SceneLight::Kind::Point:
        out.kind = raster::Light::Kind::Point;
        out.vector = l.from;
        out.inverseSquare = true;
        break;
      case SceneLight::Kind::Spot:
        out.kind = raster::Light::Kind::Spot;
        out.vector = l.from;
        out.inverseSquare = true;
        out.axis = (l.to - l.from).normalized();
        out.cosOutside = std::cos(l.coneAngle);
        out.cosInside = std::cos(std::max(0.0, l.coneAngle - l.coneDelta));
        out.beamDistribution = l.beamDistribution;
        break;
    }
    rig.lights.push_back(out);
  }
  return rig;
}

// A scene file's appearance as a back-end material. The default shader keeps the
// renderer's material, tinted by the colour.
raster::Material SceneMaterial(const Appearance& a, const raster::Material& fallback) {
  using S = Appearance::Shader;
  using M = raster::Material::Model;
  raster::Material m = fallback;
  m.opacity = a.opacity.mean();
  m.twoSided = a.twoSided;
  m.reversed = a.reversed;
  if (a.shader == S::Default) {
    m.colour = fallback.colour.cwiseProduct(a.colour);
    return m;
  }
  m.model = a.shader == S::Constant ? M::Constant
            : a.shader == S::Matte  ? M::Matte
            : a.shader == S::Metal  ? M::Metal
                                    : M::Plastic;
  m.colour = a.colour;
  m.emission = raster::Rgb::Zero();
  m.ka = a.ka;
  m.kd = a.kd;
  m.ks = a.ks;
  m.roughness = a.roughness;
  m.specularColour = a.specularColour;
  return m;
}

double SecondsSinceEpoch() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

std::string BackEndSetup::TextureError() const {
  if (texture && !texture->Error().empty()) return texture->Error();
  for (const auto& [name, t] : sceneTextures)
    if (!t->Error().empty()) return t->Error();
  return {};
}

std::string BackEndSetup::TextureReport() const {
  if (!texture) return "none";
  return std::string(texture->Opened() ? "opened" : "never needed") + ", " + std::to_string(texture->Lookups()) +
         " lookups";
}

bool WritesDepthMap(const RenderOptions& o, const Scene& scene) {
  return o.output.empty() && (scene.image.displayType == "zfile" || scene.image.displayType == "shadow");
}

std::variant<std::unique_ptr<BackEndSetup>, int> SetUpBackEnd(const RenderOptions& o, const Scene& scene,
                                                              const Camera& camera, int aa, std::ostream& err) {
  auto setup = std::make_unique<BackEndSetup>();
  raster::RenderSettings& s = setup->settings;
  s.width = camera.width;
  s.height = camera.height;
  s.aa = aa;
  s.aovs = o.aov || WritesDepthMap(o, scene);
  s.shading = o.shading;
  s.cullBackFaces = o.cullBackFaces;
  s.hiddenLine = o.hiddenLine;
  s.opacity = o.opacity;
  s.seed = o.seed;
  s.hither = camera.hither;
  s.eye = EyePoint(camera);
  s.orthographic = camera.orthographic;
  s.forward = ViewForward(camera);
  if (o.texture == "checker") {
    s.material.checkerSquares = 8;
  } else if (o.texture != "none") {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(o.texture, ec)) {
      err << "patchscan: --texture: no such file '" << o.texture << "'\n";
      return kExitUsage;
    }
    setup->texture = std::make_unique<raster::ImageTexture>(o.texture);
    s.material.texture = setup->texture.get();
  }
  const Vec3 forward = ViewForward(camera), right = ViewRight(camera);
  s.lights = scene.lights.empty() ? raster::DefaultLightRig(forward, right.cross(forward), right)
                                  : SceneLights(scene.lights);
  // The lights' shadow maps, each read once (SceneLights keeps the scene's light order,
  // less the ambient lights).
  std::size_t next = 0;
  for (const SceneLight& l : scene.lights) {
    if (l.kind == SceneLight::Kind::Ambient) continue;
    raster::Light& out = s.lights.lights[next++];
    for (const std::string& name : l.shadowNames) {
      auto& map = setup->shadowMaps[name];
      if (!map) {
        auto loaded = raster::ShadowMap::Load(name);
        if (auto* why = std::get_if<std::string>(&loaded)) {
          err << "patchscan: " << l.file << ':' << l.line << ": LightSource: " << *why << '\n';
          return kExitInputError;
        }
        map = std::move(std::get<std::unique_ptr<raster::ShadowMap>>(loaded));
      }
      out.shadows.push_back(map.get());
    }
    out.shadowBias = l.shadowBias;
    out.shadowBlur = l.shadowBlur;
    out.shadowSamples = l.shadowSamples;
  }
  // The scene's own materials, each texture opened only when a visible sample needs it.
  for (const Appearance& a : scene.appearances) {
    raster::Material m = SceneMaterial(a, s.material);
    if (!a.textureName.empty()) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(a.textureName, ec)) {
        err << "patchscan: " << scene.source << ": paintedplastic texture '" << a.textureName << "' not found\n";
        return kExitInputError;
      }
      auto& t = setup->sceneTextures[a.textureName];
      if (!t) t = std::make_unique<raster::ImageTexture>(a.textureName);
      m.texture = t.get();
    }
    s.materials.push_back(m);
  }
  s.materialOf = scene.appearanceOf;
  return setup;
}

raster::ShadowCamera LightCamera(const Camera& camera) {
  raster::ShadowCamera c;
  const Vec3 eye = EyePoint(camera), forward = ViewForward(camera), right = ViewRight(camera);
  const Vec3 up = right.cross(forward);
  c.worldToCamera.block<1, 3>(0, 0) = right.transpose();
  c.worldToCamera.block<1, 3>(1, 0) = up.transpose();
  c.worldToCamera.row(2) = ViewDepthRow(camera).transpose();  // z: the depth the map holds
  c.worldToCamera.block<2, 1>(0, 3) = -c.worldToCamera.block<2, 3>(0, 0) * eye;
  // Pixels (x right, y down) to RenderMan's screen space (x, y in [-1, 1], y up).
  Mat4 toScreen = Mat4::Identity();
  toScreen(0, 0) = 2.0 / camera.width;
  toScreen(0, 3) = -1.0;
  toScreen(1, 1) = -2.0 / camera.height;
  toScreen(1, 3) = 1.0;
  c.worldToScreen = toScreen * ScreenFromWorld(camera);
  return c;
}

std::optional<int> MakeShadows(const Scene& scene, std::ostream& err) {
  for (const SceneMakeShadow& m : scene.makeShadows)
    if (const auto why = raster::MakeShadowTexture(m.input, m.output)) {
      err << "patchscan: " << m.file << ':' << m.line << ": MakeShadow: " << *why << '\n';
      return kExitInputError;
    }
  return std::nullopt;
}

volatile std::sig_atomic_t gInterrupted = 0;
extern "C" void OnInterrupt(int) { gInterrupted = 1; }

void CatchInterrupts() {
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

ProgressSink::ProgressSink(raster::RowSink& next, int height, std::ostream& err, bool show)
    : next_(next), height_(height), err_(err), show_(show), start_(SecondsSinceEpoch()) {}

ProgressSink::~ProgressSink() {
  if (shown_) err_ << "\r" << std::string(72, ' ') << "\r" << std::flush;
}

void ProgressSink::Finish() {
  if (!show_) return;
  char line[96];
  std::snprintf(line, sizeof line, "\rrender: 100%% (%d/%d rows, %.1f s)%20s\n", rows_, height_,
                SecondsSinceEpoch() - start_, "");
  err_ << line << std::flush;
  shown_ = false;
}

bool ProgressSink::WriteRow(int y, const float* pixels) {
  if (gInterrupted) return false;
  // A few times a second: often enough to see it move, rarely enough to cost nothing.
  constexpr double kShowEverySec = 0.25;
  const double now = SecondsSinceEpoch();
  ++rows_;
  if (show_ && now - std::max(lastShown_, start_) > kShowEverySec) {
    lastShown_ = now;
    shown_ = true;
    // Time left: the rows left at the rate so far.
    const double elapsed = now - start_, left = elapsed * (height_ - rows_) / rows_;
    char line[96];
    std::snprintf(line, sizeof line, "\rrender: %3d%% (%d/%d rows, %.1f s, about %.1f s left)   ",
                  (100 * rows_) / height_, rows_, height_, elapsed, left);
    err_ << line << std::flush;
  }
  const double t0 = now;
  const bool ok = next_.WriteRow(y, pixels);
  outputSeconds_ += SecondsSinceEpoch() - t0;
  return ok;
}

}  // namespace patchscan::cli

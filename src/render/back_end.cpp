#include "render/back_end.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "raster/cube_environment.h"
#include "render/load.h"
#include "scene/rib/reader.h"

namespace patchscan::render {
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
            : a.shader == S::Metal || a.shader == S::ShinyMetal ? M::Metal
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
std::string RequestName(SceneMakeTexture::Kind kind) {
  using K = SceneMakeTexture::Kind;
  return kind == K::Shadow ? "MakeShadow" : kind == K::LatLong ? "MakeLatLongEnvironment" : "MakeCubeFaceEnvironment";
}

// Where the depth or shadow map `name` comes from, for a warning that it is missing: the
// frame of `ribFile` whose Display writes it, or the MakeShadow of `scene` that makes it
// and the frame that writes that one's depth map.
std::string WhereMade(const std::string& name, const Scene& scene, const std::string& ribFile) {
  const std::vector<RibFrame> frames = RibFrames(ribFile);
  auto writer = [&](const std::string& file) -> std::string {
    for (const RibFrame& f : frames)
      if (f.display == file) return "frame " + std::to_string(f.number) + " of " + ribFile + " writes " + file;
    return "no frame of " + ribFile + " writes " + file;
  };
  for (const SceneMakeTexture& m : scene.makeTextures)
    if (m.output == name)
      return RequestName(m.kind) + " at " + m.file + ':' + std::to_string(m.line) + " makes it from " + m.input + "; " + writer(m.input);
  return writer(name);
}

// --bump's and --environment's value: the file and the number after its last ':' (1
// without one); nullopt when that is not a finite number.
std::optional<std::pair<std::string, double>> FileAndNumber(const std::string& text) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string::npos) return std::pair{text, 1.0};
  const std::string amplitude = text.substr(colon + 1);
  char* end = nullptr;
  const double a = std::strtod(amplitude.c_str(), &end);
  if (amplitude.empty() || *end != '\0' || !std::isfinite(a)) return std::nullopt;
  return std::pair{text.substr(0, colon), a};
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

Result<std::unique_ptr<BackEndSetup>> SetUpBackEnd(const RenderOptions& o, const Scene& scene, const Camera& camera,
                                                   int aa) {
  auto setup = std::make_unique<BackEndSetup>();
  raster::RenderSettings& s = setup->settings;
  s = SettingsFor(camera, aa);
  const bool depthMap = WritesDepthMap(o, scene);
  s.aovs = o.aov || depthMap;
  if (depthMap) {
    const std::string& f = scene.image.depthFilter;
    using D = raster::DepthFilter;
    s.depthFilter = f == "max" ? D::Max : f == "average" ? D::Average : f == "midpoint" ? D::Midpoint : D::Min;
  }
  s.shading = o.shading;
  s.cullBackFaces = o.cullBackFaces;
  s.hiddenLine = o.hiddenLine;
  s.opacity = o.opacity;
  s.seed = o.seed;
  if (o.texture == "checker") {
    s.material.checkerSquares = 8;
  } else if (o.texture != "none") {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(o.texture, ec))
      return Failure{Outcome::BadOption, "--texture: no such file '" + o.texture + "'"};
    setup->texture = std::make_unique<raster::ImageTexture>(o.texture);
    s.material.texture = setup->texture.get();
  }
  // Textures by file name, each opened only when a visible sample needs it.
  const auto texture = [&](const std::string& name) {
    auto& t = setup->sceneTextures[name];
    if (!t) t = std::make_unique<raster::ImageTexture>(name);
    return t.get();
  };
  const auto exists = [](const std::string& name) {
    std::error_code ec;
    return std::filesystem::is_regular_file(name, ec);
  };
  if (!o.bump.empty()) {
    const auto bump = FileAndNumber(o.bump);
    if (!bump) return Failure{Outcome::BadOption, "--bump: expected FILE or FILE:AMPLITUDE, not '" + o.bump + "'"};
    if (!exists(bump->first)) return Failure{Outcome::BadOption, "--bump: no such file '" + bump->first + "'"};
    s.material.bump = {texture(bump->first), bump->second};
  }
  if (!o.normalMap.empty()) {
    if (!exists(o.normalMap)) return Failure{Outcome::BadOption, "--normal-map: no such file '" + o.normalMap + "'"};
    s.material.normalMap = texture(o.normalMap);
  }
  if (!o.environment.empty()) {
    const auto env = FileAndNumber(o.environment);
    if (!env) return Failure{Outcome::BadOption, "--environment: expected FILE or FILE:KR, not '" + o.environment + "'"};
    if (!exists(env->first)) return Failure{Outcome::BadOption, "--environment: no such file '" + env->first + "'"};
    s.material.environment = {texture(env->first), env->second};
  }
  if (!scene.lights.empty()) s.lights = SceneLights(scene.lights);
  // The lights' shadow maps, each read once (SceneLights keeps the scene's light order,
  // less the ambient lights).
  std::size_t next = 0;
  std::map<std::string, std::string> unreadable;  // map file: why it could not be read
  for (const SceneLight& l : scene.lights) {
    if (l.kind == SceneLight::Kind::Ambient) continue;
    raster::Light& out = s.lights.lights[next++];
    for (const std::string& name : l.shadowNames) {
      // Each map read once, whichever lights share it; one that cannot be read leaves each
      // light that names it unshadowed, with a warning naming that light.
      if (!setup->shadowMaps.contains(name) && !unreadable.contains(name)) {
        auto loaded = raster::ShadowMap::Load(name);
        if (auto* why = std::get_if<std::string>(&loaded))
          unreadable[name] = *why + " (" + WhereMade(name, scene, o.file) + ")";
        else
          setup->shadowMaps[name] = std::move(std::get<std::unique_ptr<raster::ShadowMap>>(loaded));
      }
      if (auto it = setup->shadowMaps.find(name); it != setup->shadowMaps.end())
        out.shadows.push_back(it->second.get());
      else
        setup->warnings.push_back(l.file + ':' + std::to_string(l.line) + ": LightSource: " + unreadable[name] +
                                  "; the light casts no shadow through it");
    }
    out.shadowBias = l.shadowBias;
    out.shadowBlur = l.shadowBlur;
    out.shadowSamples = l.shadowSamples;
  }
  // The scene's own materials.
  for (const Appearance& a : scene.appearances) {
    raster::Material m = SceneMaterial(a, s.material);
    if (!a.textureName.empty()) {
      if (!exists(a.textureName))
        return Failure{Outcome::InputError,
                       scene.source + ": paintedplastic texture '" + a.textureName + "' not found"};
      m.texture = texture(a.textureName);
    }
    if (!a.bumpName.empty()) {
      if (!exists(a.bumpName))
        return Failure{Outcome::InputError, scene.source + ": bumpy texture '" + a.bumpName + "' not found"};
      m.bump = {texture(a.bumpName), a.bumpScale};
    }
    if (a.shader == Appearance::Shader::ShinyMetal) {
      // Its own map, or none ("" : no reflection, as the shader's default).
      m.environment = {nullptr, a.kr};
      if (!a.environmentName.empty()) {
        if (!exists(a.environmentName))
          return Failure{Outcome::InputError, scene.source + ": shinymetal environment map '" + a.environmentName +
                                                  "' not found (it is read from the working directory)"};
        m.environment.map = texture(a.environmentName);
      }
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

std::vector<std::string> MakeTextures(const Scene& scene, const std::string& ribFile) {
  std::vector<std::string> warnings;
  for (const SceneMakeTexture& m : scene.makeTextures) {
    using K = SceneMakeTexture::Kind;
    const auto why = m.kind == K::Shadow    ? raster::MakeShadowTexture(m.input, m.output)
                     : m.kind == K::LatLong ? raster::MakeLatLongEnvironment(m.input, m.output)
                                            : raster::MakeCubeFaceEnvironment(m.faces, m.fovDeg, m.output);
    if (!why) continue;
    std::string input = m.input;  // a cube's first face that is missing, if one is
    std::error_code ec;
    if (m.kind == K::CubeFace)
      for (auto face = m.faces.rbegin(); face != m.faces.rend(); ++face)
        if (!std::filesystem::exists(*face, ec)) input = *face;
    warnings.push_back(m.file + ':' + std::to_string(m.line) + ": " + RequestName(m.kind) + ": " + *why + " (" +
                       WhereMade(input, scene, ribFile) + "); " + m.output + " is not made");
  }
  return warnings;
}

}  // namespace patchscan::render

// The RIB requests of the camera and image, the transformations and the appearance.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "patch/camera.h"
#include "scene/rib/parser.h"
#include "scene/text_file.h"

namespace patchscan::rib {

bool RibParser::Format(const Request& r) {
  if (!Numbers(r, 3)) return false;
  const double w = num_[0], h = num_[1];
  if (!(w >= 1 && h >= 1 && w <= kMaxImageSide && h <= kMaxImageSide && w == std::floor(w) && h == std::floor(h)))
    return Fail(r.line, "Format: the image size must be whole numbers from 1 to " + std::to_string(kMaxImageSide));
  if (!(num_[2] > 0)) return Fail(r.line, "Format: the pixel aspect ratio must be positive");
  if (num_[2] != 1.0) Warn(r.line, "pixelaspect", "Format: pixel aspect ratios other than 1 are not supported: square pixels");
  scene_.image.size = std::make_pair(static_cast<int>(w), static_cast<int>(h));
  return true;
}

bool RibParser::Projection(const Request& r) {
  std::string name;
  std::vector<Param> params;
  if (!NameAndParams(r, &name, &params)) return false;
  if (name != "perspective" && name != "orthographic")
    return Fail(r.line, "Projection: unknown projection " + Shown(name) + " (known: \"perspective\", \"orthographic\")");
  scene_.image.orthographic = name == "orthographic";
  double& fov = scene_.image.fovDeg;
  fov = kRibDefaultFovDeg;
  for (const Param& p : params) {
    if (p.name == "fov" && !scene_.image.orthographic) {
      if (!ParamNumbers(r, p, 1, &fov)) return false;
      if (!(fov >= kMinFovDeg && fov <= kMaxFovDeg))
        return Fail(p.value->line, "Projection: fov must be from " + std::to_string(kMinFovDeg) + " to " + std::to_string(kMaxFovDeg) + " degrees");
    } else {
      IgnoreParam(r, p);
    }
  }
  // The projection resets the camera transformation (RenderMan Interface 3.2: it
  // defines camera space).
  attr_.transform = Mat4::Identity();
  return true;
}

bool RibParser::ScreenWindow(const Request& r) {
  if (!Numbers(r, 4)) return false;
  if (num_[0] == num_[1] || num_[2] == num_[3]) return Fail(r.line, "ScreenWindow: the window is empty");
  scene_.image.screenWindow = Vec4(num_[0], num_[1], num_[2], num_[3]);
  return true;
}

bool RibParser::CropWindow(const Request& r) {
  if (!Numbers(r, 4)) return false;
  const double* w = num_.data();
  if (!(0.0 <= w[0] && w[0] < w[1] && w[1] <= 1.0 && 0.0 <= w[2] && w[2] < w[3] && w[3] <= 1.0))
    return Fail(r.line, "CropWindow: expected 0 <= xmin < xmax <= 1 and 0 <= ymin < ymax <= 1");
  scene_.image.cropWindow = Vec4(w[0], w[1], w[2], w[3]);
  return true;
}

bool RibParser::Clipping(const Request& r) {
  if (!Numbers(r, 2)) return false;
  if (!(num_[0] > 0 && num_[1] > num_[0])) return Fail(r.line, "Clipping: expected 0 < near < far");
  scene_.image.hither = num_[0];
  return true;
}

bool RibParser::PixelSamples(const Request& r) {
  if (!Numbers(r, 2)) return false;
  if (!(num_[0] >= 1 && num_[1] >= 1)) return Fail(r.line, "PixelSamples: expected at least 1 sample each way");
  const double side = std::round(std::sqrt(num_[0] * num_[1]));
  if (num_[0] != num_[1] || side > 8)
    Warn(r.line, "PixelSamples", "PixelSamples: a square grid of 1 to 8 samples a side is used");
  scene_.image.pixelSamples = static_cast<int>(std::clamp(side, 1.0, 8.0));
  return true;
}

bool RibParser::Display(const Request& r) {
  std::string name, type;
  if (!StringArg(r, 0, &name) || !StringArg(r, 1, &type)) return false;
  // After the mode, the display driver's parameters: "compression" (as RenderMan's tiff and
  // openexr drivers take it; raster/image_writer.h lists each format's) is kept.
  std::string compression;
  if (r.args.size() > 3) {
    std::vector<Param> params;
    if (!Params(r, 3, &params)) return false;
    for (const Param& p : params) {
      if (p.name == "compression") {
        if (!ParamString(r, p, &compression)) return false;
      } else {
        IgnoreParam(r, p);
      }
    }
  }
  // A name starting with '+' adds a further display: only the first is written.
  if (type != "framebuffer" && !name.empty() && name[0] != '+') {
    scene_.image.displayName = name;
    scene_.image.displayType = type;
    scene_.image.displayCompression = compression;
    scene_.image.displayLine = r.line;
  }
  return true;
}

bool RibParser::SetTransform(const Request& r, const Mat4& m) {
  attr_.transform = m;
  return CheckTransform(r);
}

bool RibParser::Concat(const Request& r, const Mat4& m) {
  attr_.transform = attr_.transform * m;
  return CheckTransform(r);
}

bool RibParser::CheckTransform(const Request& r) {
  if (!attr_.transform.allFinite()) return Fail(r.line, r.name + ": the transformation is no longer finite");
  return true;
}

bool RibParser::sawWorldOpen() const {
  for (const Block& b : blocks_)
    if (b.kind == Block::Kind::World) return true;
  return false;
}

bool RibParser::Rotate(const Request& r) {
  if (!Numbers(r, 4)) return false;
  const Vec3 axis(num_[1], num_[2], num_[3]);
  if (axis.norm() == 0.0) return Fail(r.line, "Rotate: the axis is zero");
  Mat4 m = Mat4::Identity();
  m.block<3, 3>(0, 0) = Eigen::AngleAxisd(num_[0] * kRadPerDeg, axis.normalized()).toRotationMatrix();
  return Concat(r, m);
}

bool RibParser::Orientation(const Request& r) {
  std::string o;
  if (!StringArg(r, 0, &o)) return false;
  if (o == "outside" || o == "lh") {
    attr_.insideOrientation = false;
  } else if (o == "inside" || o == "rh") {
    attr_.insideOrientation = true;
  } else {
    return Fail(r.line, "Orientation: expected \"outside\", \"inside\", \"lh\" or \"rh\", found " + Shown(o));
  }
  return true;
}

bool RibParser::Sides(const Request& r) {
  if (!Numbers(r, 1)) return false;
  if (num_[0] != 1 && num_[0] != 2) return Fail(r.line, "Sides: expected 1 or 2");
  attr_.appearance.twoSided = num_[0] == 2;
  return true;
}

bool RibParser::SurfaceShader(const Request& r) {
  std::string name;
  std::vector<Param> params;
  if (!NameAndParams(r, &name, &params)) return false;
  Appearance& a = attr_.appearance;
  using S = Appearance::Shader;
  // The standard shaders' defaults (RenderMan Interface 3.2, appendix A).
  if (name == "constant") {
    a.shader = S::Constant;
  } else if (name == "matte") {
    a.shader = S::Matte;
    a.ka = 1.0;
    a.kd = 1.0;
  } else if (name == "metal" || name == "shinymetal") {
    // shinymetal (The RenderMan Companion; RenderMan's example shaders): metal reflecting
    // Kr times its colour times the environment map "texturename" in the mirror direction.
    a.shader = name == "metal" ? S::Metal : S::ShinyMetal;
    a.ka = 1.0;
    a.ks = 1.0;
    a.roughness = 0.1;
    a.kr = 1.0;
  } else if (name == "plastic" || name == "paintedplastic") {
    a.shader = name == "plastic" ? S::Plastic : S::PaintedPlastic;
    a.ka = 1.0;
    a.kd = 0.5;
    a.ks = 0.5;
    a.roughness = 0.1;
    a.specularColour = Vec3(1, 1, 1);
  } else {
    Warn(r.line, "shader " + name, "Surface: unknown shader " + Shown(name) + ": the default material is used");
    a.shader = S::Default;
    return true;
  }
  a.textureName.clear();
  a.environmentName.clear();
  const bool metal = a.shader == S::Metal || a.shader == S::ShinyMetal;
  for (const Param& p : params) {
    bool ok = true;
    if (p.name == "Ka" && a.shader != S::Constant) ok = ParamNumbers(r, p, 1, &a.ka);
    else if (p.name == "Kd" && a.shader != S::Constant && !metal) ok = ParamNumbers(r, p, 1, &a.kd);
    else if (p.name == "Ks" && (metal || a.shader == S::Plastic || a.shader == S::PaintedPlastic)) ok = ParamNumbers(r, p, 1, &a.ks);
    else if (p.name == "Kr" && a.shader == S::ShinyMetal) ok = ParamNumbers(r, p, 1, &a.kr);
    else if (p.name == "texturename" && a.shader == S::ShinyMetal) ok = ParamString(r, p, &a.environmentName);
    else if (p.name == "roughness" && (metal || a.shader == S::Plastic || a.shader == S::PaintedPlastic)) {
      ok = ParamNumbers(r, p, 1, &a.roughness);
      if (ok && !(a.roughness > 0)) return Fail(p.value->line, "Surface: roughness must be positive");
    } else if (p.name == "specularcolor" && (a.shader == S::Plastic || a.shader == S::PaintedPlastic)) {
      ok = ParamVec3(r, p, &a.specularColour);
    } else if (p.name == "texturename" && a.shader == S::PaintedPlastic) {
      ok = ParamString(r, p, &a.textureName);
      if (ok && !a.textureName.empty()) {
        std::filesystem::path path(a.textureName);
        if (path.is_relative()) a.textureName = (std::filesystem::path(file_).parent_path() / path).string();
      }
    } else {
      IgnoreParam(r, p);
    }
    if (!ok) return false;
  }
  return true;
}

bool RibParser::DisplacementShader(const Request& r) {
  std::string name;
  std::vector<Param> params;
  if (!NameAndParams(r, &name, &params)) return false;
  Appearance& a = attr_.appearance;
  a.bumpName.clear();
  a.bumpScale = 1.0;
  if (name != "bumpy") {
    Warn(r.line, "displacement " + name,
         "Displacement: unknown shader " + Shown(name) + ": the surface is not displaced");
    return true;
  }
  // bumpy moves P by Km * amplitude * texture(texturename) along N and takes the moved
  // surface's normal; here the surface stays and its normal is bumped (RenderMan Interface
  // 3.2, 4.2.5: an implementation without the Displacements capability bumps).
  double km = 1.0, amplitude = 1.0;
  for (const Param& p : params) {
    bool ok = true;
    if (p.name == "Km") ok = ParamNumbers(r, p, 1, &km);
    else if (p.name == "amplitude") ok = ParamNumbers(r, p, 1, &amplitude);
    else if (p.name == "texturename") {
      ok = ParamString(r, p, &a.bumpName);
      if (ok && !a.bumpName.empty()) {
        std::filesystem::path path(a.bumpName);
        if (path.is_relative()) a.bumpName = (std::filesystem::path(file_).parent_path() / path).string();
      }
    } else IgnoreParam(r, p);
    if (!ok) return false;
  }
  a.bumpScale = km * amplitude;
  if (!std::isfinite(a.bumpScale)) return Fail(r.line, "Displacement: Km and amplitude must be finite");
  return true;
}

bool RibParser::LightSource(const Request& r) {
  std::string name;
  if (!StringArg(r, 0, &name)) return false;
  if (r.args.size() < 2) return Fail(r.line, "LightSource expects a shader name and a light handle");
  std::vector<Param> params;
  if (!Params(r, 2, &params)) return false;
  SceneLight l;
  l.line = r.line;
  l.file = file_;
  l.shadowBias = shadowBias_;
  using K = SceneLight::Kind;
  // The standard lights, and the shadowing ones of RenderMan's light library.
  const bool shadowing = name == "shadowspot" || name == "shadowdistant" || name == "shadowpoint";
  if (name == "ambientlight") l.kind = K::Ambient;
  else if (name == "distantlight" || name == "shadowdistant") l.kind = K::Distant;
  else if (name == "pointlight" || name == "shadowpoint") l.kind = K::Point;
  else if (name == "spotlight" || name == "shadowspot") l.kind = K::Spot;
  else {
    Warn(r.line, "light " + name, "LightSource: unknown light shader " + Shown(name) + ": skipped");
    return true;
  }
  double intensity = 1.0;
  Vec3 colour(1, 1, 1);
  l.coneAngle = kSpotConeDeg * kRadPerDeg;
  l.coneDelta = kSpotDeltaDeg * kRadPerDeg;
  for (const Param& p : params) {
    bool ok = true;
    if (p.name == "intensity") ok = ParamNumbers(r, p, 1, &intensity);
    else if (p.name == "lightcolor") ok = ParamVec3(r, p, &colour);
    else if (p.name == "from" && l.kind != K::Ambient) ok = ParamVec3(r, p, &l.from);
    else if (p.name == "to" && (l.kind == K::Distant || l.kind == K::Spot)) ok = ParamVec3(r, p, &l.to);
    else if (p.name == "coneangle" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.coneAngle);
    else if (p.name == "conedeltaangle" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.coneDelta);
    else if (p.name == "beamdistribution" && l.kind == K::Spot) ok = ParamNumbers(r, p, 1, &l.beamDistribution);
    else if (shadowing && (p.name == "shadowname" || (name == "shadowpoint" && p.name.size() == 4 && p.name[0] == 's' &&
                                                       p.name[1] == 'f'))) {
      // shadowpoint: sfpx sfnx sfpy sfny sfpz sfnz, the six faces of a cube about it.
      std::string map;
      ok = ParamString(r, p, &map);
      if (ok && !map.empty()) l.shadowNames.push_back(map);
    } else if (shadowing && p.name == "bias") ok = ParamNumbers(r, p, 1, &l.shadowBias);
    else if (shadowing && p.name == "blur") ok = ParamNumbers(r, p, 1, &l.shadowBlur);
    else if (shadowing && p.name == "samples") {
      double samples = 16;
      ok = ParamNumbers(r, p, 1, &samples);
      // Total samples, as the shaders take them: a square grid of about as many.
      l.shadowSamples = std::clamp(static_cast<int>(std::lround(std::sqrt(std::max(samples, 1.0)))), 1, 16);
    } else IgnoreParam(r, p);
    if (!ok) return false;
  }
  if ((l.kind == K::Distant || l.kind == K::Spot) && l.from == l.to)
    return Fail(r.line, "LightSource: \"from\" and \"to\" are the same point");
  l.colour = intensity * colour;
  // From the current space into world space (camera space before WorldBegin: moved to
  // world space there).
  l.from = (attr_.transform * l.from.homogeneous()).head<3>();
  l.to = (attr_.transform * l.to.homogeneous()).head<3>();
  if (!(l.shadowBias >= 0.0) || !(l.shadowBlur >= 0.0) || !std::isfinite(l.shadowBias) || !std::isfinite(l.shadowBlur))
    return Fail(r.line, "LightSource: \"bias\" and \"blur\" are not negative");
  scene_.lights.push_back(l);
  return true;
}

bool RibParser::Hider(const Request& r) {
  std::string type;
  std::vector<Param> params;
  if (!NameAndParams(r, &type, &params)) return false;
  if (type != "hidden") Warn(r.line, "Hider", "Hider " + Shown(type) + " is not supported here: the scan-line hider is used");
  for (const Param& p : params) {
    if (p.name != "depthfilter" || type != "hidden") {
      IgnoreParam(r, p);
      continue;
    }
    std::string filter;
    if (!ParamString(r, p, &filter)) return false;
    if (filter == "min" || filter == "max" || filter == "average" || filter == "midpoint")
      scene_.image.depthFilter = filter;
    else
      Warn(p.value->line, "depthfilter", "Hider: depthfilter " + Shown(filter) +
                                             " is not min, max, average or midpoint: min is used");
  }
  return true;
}

bool RibParser::Option(const Request& r) {
  // Only the shadow bias changes the picture here; other options are skipped, as before.
  std::string name;
  std::vector<Param> params;
  if (!NameAndParams(r, &name, &params)) return false;
  if (name != "shadow") {
    Warn(r.line, "Option " + name, "Option " + Shown(name) + " is not supported here: skipped");
    return true;
  }
  for (const Param& p : params) {
    if (p.name != "bias") {
      IgnoreParam(r, p);
      continue;
    }
    double bias = 0.0;
    if (!ParamNumbers(r, p, 1, &bias)) return false;
    if (!(bias >= 0.0) || !std::isfinite(bias)) return Fail(p.value->line, "Option: shadow \"bias\" is not negative");
    shadowBias_ = bias;
  }
  return true;
}

bool RibParser::MakeTexture(const Request& r) {
  // MakeShadow picturename texturename, MakeLatLongEnvironment picturename texturename
  // filter swidth twidth, MakeCubeFaceEnvironment px nx py ny pz nz texturename fov filter
  // swidth twidth: run before the frame renders (a depth map of an earlier frame becomes a
  // shadow texture; images of the surroundings an environment texture, filtered as
  // OpenImageIO's maketx filters, whatever the request's filter). The texture is written to
  // the working directory, as Display writes; a depth map is read from there (a frame wrote
  // it), environment images, which the scene brings, beside the scene file.
  using K = SceneMakeTexture::Kind;
  SceneMakeTexture make;
  make.kind = r.name == "MakeShadow" ? K::Shadow : r.name == "MakeLatLongEnvironment" ? K::LatLong : K::CubeFace;
  make.file = file_;
  make.line = r.line;
  const auto besideScene = [&](std::string* in) {
    if (std::filesystem::path(*in).is_relative()) *in = (std::filesystem::path(file_).parent_path() / *in).string();
  };
  if (make.kind == K::CubeFace) {
    for (size_t k = 0; k < make.faces.size(); ++k) {
      if (!StringArg(r, k, &make.faces[k])) return false;
      besideScene(&make.faces[k]);
    }
    if (!StringArg(r, 6, &make.output)) return false;
    if (r.args.size() < 8 || r.args[7].kind != Value::Kind::Number)
      return Fail(r.line, r.name + " expects the faces' field of view as argument 8");
    make.fovDeg = r.args[7].numbers[0];
    // Narrower faces would leave directions no face holds.
    if (!(make.fovDeg >= 90.0 && make.fovDeg < 180.0))
      return Fail(r.args[7].line, r.name + ": the field of view must be at least 90 and less than 180 degrees");
    make.input = make.faces[0];
  } else {
    if (!StringArg(r, 0, &make.input) || !StringArg(r, 1, &make.output)) return false;
    if (make.kind == K::LatLong) besideScene(&make.input);
  }
  scene_.makeTextures.push_back(std::move(make));
  return true;
}

}  // namespace patchscan::rib

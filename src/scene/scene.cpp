#include "scene/scene.h"

#include <algorithm>
#include <filesystem>

#include "core/ascii.h"
#include "scene/bpt_reader.h"
#include "scene/cad_library.h"
#include "scene/obj_reader.h"
#include "scene/rib/reader.h"

namespace patchscan {

Bounds3 Scene::WorldBounds() const {
  Bounds3 b;
  for (const Surface& s : surfaces) b.Extend(patchscan::WorldBounds(s));
  for (const ScenePolygons& p : polygons)
    for (const PolygonVertex& v : p.mesh.vertices) b.Extend(v.position);
  return b;
}

void Scene::FaceCamera(const Camera& camera) {
  const Vec3 eye = EyePoint(camera), forward = ViewForward(camera);
  for (Surface& s : surfaces)
    if (auto* ribbon = std::get_if<CurveRibbon>(&s.shape)) {
      if (camera.orthographic) ribbon->FaceAxis(forward);
      else ribbon->FaceEye(eye);
    }
}

std::variant<Scene, SourceError> LoadScene(const std::string& path, const LoadOptions& options) {
  const std::filesystem::path p(path);
  const std::string ext = AsciiLower(p.extension().string());  // "TEAPOT.RIB" is a RIB file too
  if (ext == ".rib" || (ext == ".gz" && AsciiLower(p.stem().extension().string()) == ".rib")) return ReadRib(path, options);
  if (ext == ".obj") return ReadObj(path, ObjOptions{options.objScheme});
  if (IsCadExtension(ext)) return ReadCadModel(path, options.cadAsNurbs);
  if (ext != ".bpt")
    return SourceError{path, 0, "unknown scene format '" + ext +
                                    "' (known: .bpt, .rib, .rib.gz, .obj, .step, .stp, .iges, .igs, .brep)"};
  auto read = ReadBpt(path);
  if (auto* e = std::get_if<SourceError>(&read)) return *e;
  Scene scene;
  scene.source = path;
  for (const BptPatch& p : std::get<BptFile>(read).patches) {
    scene.surfaces.push_back(Surface{BicubicPatch(p.cv), Affine3::Identity()});
    scene.sourceLines.push_back(p.line);
    scene.sourceFiles.push_back(path);
  }
  return scene;
}

}  // namespace patchscan

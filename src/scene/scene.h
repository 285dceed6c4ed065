// A scene as read from a file: surfaces placed in the world, each remembering the line it
// came from. Readers are chosen by file extension.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "patch/camera.h"
#include "patch/polygon.h"
#include "scene/source_error.h"
#include "patch/surface.h"
#include "patch/tessellate.h"

namespace patchscan {

// How a surface looks, as RenderMan's attributes say (RenderMan Interface 3.2: Color,
// Opacity, Surface, Sides, and the standard shaders of its appendix A).
struct Appearance {
  enum class Shader { Default, Constant, Matte, Plastic, Metal, PaintedPlastic, ShinyMetal };
  Shader shader = Shader::Default;  // Default: the renderer's own material
  Vec3 colour = Vec3(1, 1, 1);      // Cs
  Vec3 opacity = Vec3(1, 1, 1);     // Os
  double ka = 1.0, kd = 0.5, ks = 0.5, roughness = 0.1;
  Vec3 specularColour = Vec3(1, 1, 1);
  std::string textureName;          // paintedplastic: a path, resolved against the scene file
  // shinymetal: its environment map (as given: relative to the working directory, where
  // MakeLatLongEnvironment writes one; "": none) and Kr, the share of it reflected.
  std::string environmentName;
  double kr = 1.0;
  // Displacement "bumpy" (RenderMan Interface 3.2, appendix A), applied as a bump map (Blinn
  // 1978): its height texture (a path as above; "": none) and the scale of its values, Km
  // times amplitude, in world units.
  std::string bumpName;
  double bumpScale = 1.0;
  bool twoSided = true;             // Sides 2 (the default) or 1
  bool reversed = false;            // the front is the side the normal points away from
  bool operator==(const Appearance&) const = default;
};

// A shadow light's depth bias where neither the light nor Option "shadow" "bias" gives one:
// the shadowspot shader's default in RenderMan's standard light library (world units).
constexpr double kDefaultShadowBias = 0.05;

// A light source in world space (RenderMan's ambientlight, distantlight, pointlight and
// spotlight). Intensities multiply the colour; point and spot lights fall off as 1/d^2.
struct SceneLight {
  enum class Kind { Ambient, Distant, Point, Spot };
  Kind kind = Kind::Distant;
  Vec3 colour = Vec3(1, 1, 1);  // lightcolor times intensity
  Vec3 from = Vec3(0, 0, 0), to = Vec3(0, 0, 1);  // world space
  double coneAngle = 0.0, coneDelta = 0.0;        // spot: radians
  double beamDistribution = 2.0;                   // spot: cosine exponent
  // Shadow maps (shadowspot, shadowdistant: one; shadowpoint: its six faces), looked up
  // with the depth bias (world units), the blur (a fraction of the map's width) and
  // samples x samples points; "" where not given.
  std::vector<std::string> shadowNames;
  double shadowBias = kDefaultShadowBias, shadowBlur = 0.0;
  int shadowSamples = 4;
  std::string file;  // where the light was declared, for messages
  int line = 0;
};

// A texture made before the frame is rendered: MakeShadow (a shadow texture of a depth map),
// MakeLatLongEnvironment (an environment texture of a lat-long image) or
// MakeCubeFaceEnvironment (one of six face images, `input` and `faces`, px nx py ny pz nz,
// rendered with a `fovDeg` field of view).
struct SceneMakeTexture {
  enum class Kind { Shadow, LatLong, CubeFace };
  Kind kind = Kind::Shadow;
  std::string input, output;
  std::array<std::string, 6> faces;  // CubeFace: input is faces[0]
  double fovDeg = 90.0;
  std::string file;
  int line = 0;
};

// What a scene file says about the image beyond its geometry.
struct SceneImage {
  std::optional<Mat4> cameraFromWorld;      // the transformation at WorldBegin: a RIB camera
  bool orthographic = false;                // Projection "orthographic"
  double fovDeg = 90.0;                     // Projection "perspective" "fov"
  std::optional<Vec4> screenWindow;         // ScreenWindow (left, right, bottom, top)
  std::optional<Vec4> cropWindow;           // CropWindow (xmin, xmax, ymin, ymax), NDC: y down
  std::optional<std::pair<int, int>> size;  // Format
  std::optional<double> hither;             // Clipping's near
  std::optional<int> pixelSamples;          // PixelSamples, as the side of a square grid
  std::string displayName;                  // Display's file name ("" when none)
  std::string displayType;                  // its type: "file", "tiff", ..., "zfile", "shadow"
  std::string displayCompression;           // its "compression" parameter ("" when none)
  int displayLine = 0;                      // the Display request's line in the scene file
  // How a depth map's pixel depth comes from its samples' (Hider "hidden" "depthfilter"):
  // the nearest, the farthest, their mean, or Woo's midpoint between each sample's two
  // nearest surfaces (raster::DepthFilter).
  std::string depthFilter = "min";
};

// A subdivision cage of the scene, for `patchscan info` (its faces are among the scene's
// surfaces).
struct SceneCage {
  std::string file;
  int line = 0;  // where it is defined: the request, or an .obj file's first face
  SubdivScheme scheme = SubdivScheme::CatmullClark;
  SubdivCounts counts;
};

// The polygons of one request (Polygon, GeneralPolygon, PointsPolygons,
// PointsGeneralPolygons), triangulated, in world space.
struct ScenePolygons {
  PolygonMesh mesh;
  std::string file;
  int line = 0;
};

// What a CAD file holds beyond its surfaces, for `patchscan info` (scene/cad_reader.h).
// Counts are of the prepared shapes: a part placed several times counts once.
struct SceneCad {
  std::vector<std::pair<std::string, int>> faceKinds;  // faces by surface type, as in the file
  int faces = 0, edges = 0, wires = 0;
  int skipped = 0;                // faces that could not be converted (warnings say why)
  int instances = 0;              // placed parts
  double largestTolerance = 0.0;  // the largest edge tolerance the file states
  double largestGap = 0.0;        // the widest gap measured between two faces along an edge
  double largestJoint = 0.0;      // the widest joint between consecutive edges of a wire
  int colours = 0;                // distinct colours of faces, solids, parts or instances
  std::vector<std::string> tree;  // the assembly: one line per node, two spaces a level
  // The model meshed by Open CASCADE (BRepMesh) with a chord deviation of at most the
  // argument (model units), in world space, each face's triangles taking the surface id of
  // its first piece: what --mode tess renders of a CAD file.
  std::function<TessMesh(double deflection)> mesh;
};

struct Scene {
  std::string source;             // the file it was read from
  std::vector<Surface> surfaces;
  std::vector<int> sourceLines;   // per surface, the line that defines it
  std::vector<std::string> sourceFiles;  // per surface, the file that defines it (RIB archives)
  std::vector<Appearance> appearances;   // distinct appearances (empty: the renderer's default)
  std::vector<std::uint32_t> appearanceOf;  // per surface, into appearances (empty when it is)
  std::vector<SceneLight> lights;        // empty: the renderer's default lights
  SceneImage image;
  std::vector<std::string> warnings;     // statements read and skipped, file:line: what
  std::vector<SceneMakeTexture> makeTextures;  // in the order read, to run before rendering
  std::vector<SceneCage> cages;
  // Polygons come after the surfaces in the surface ids: polygons[k] is surface id
  // surfaces.size() + k, and appearanceOf (when not empty) covers them after the surfaces.
  std::vector<ScenePolygons> polygons;
  std::optional<SceneCad> cad;           // a CAD file's facts (none for other formats)

  // How many surface ids the scene has: its surfaces, then its polygon meshes.
  std::size_t Ids() const { return surfaces.size() + polygons.size(); }

  // Room for `more` surfaces in every per-surface vector at once (appearanceOf too when
  // `withAppearances`), growing at least by doubling across calls. A Surface is a kilobyte:
  // growing one by one moved each about twice into fresh pages (a third of a 2,688-face
  // cage's load).
  // Inline: the CAD module (scene/cad_library.h) calls it and links none of scene.cpp.
  void ReserveSurfaces(std::size_t more, bool withAppearances) {
    const auto grow = [more](auto& v) {
      if (v.size() + more > v.capacity()) v.reserve(std::max(v.size() + more, 2 * v.capacity()));
    };
    grow(surfaces), grow(sourceLines), grow(sourceFiles);
    if (withAppearances) grow(appearanceOf);
  }

  // A conservative world-space box of the whole scene.
  Bounds3 WorldBounds() const;
  // Turns every curve's ribbons (patch/curves.h) to face the camera's eye (or, for an
  // orthographic camera, its view axis). Before this they face along +z.
  void FaceCamera(const Camera& camera);
};

struct LoadOptions {
  int frame = -1;  // RIB: the FrameBegin number to read; -1: the first frame
  SubdivScheme objScheme = SubdivScheme::CatmullClark;  // .obj: how its cage is subdivided
  // CAD: every face as trimmed NURBS pieces (Open CASCADE's NurbsConvert), its planes and
  // quadrics too, which are otherwise their analytic shapes; RenderMan trims NuPatches only,
  // so this is what a RIB file can hold.
  bool cadAsNurbs = false;
};

// Read a scene file. Known extensions: .bpt (Bézier patch text), .rib (RenderMan
// Interface Bytestream), .obj (Wavefront, read as a subdivision cage) and CAD models
// (scene/cad_library.h). Errors name file:line.
std::variant<Scene, SourceError> LoadScene(const std::string& path, const LoadOptions& options = {});

}  // namespace patchscan

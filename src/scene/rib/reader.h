// Reader for RenderMan Interface Bytestream scenes (.rib, and gzip-compressed .rib.gz): the
// subset of the RenderMan Interface Specification 3.2 that describes parametric surfaces,
// their camera, lights and materials. Supported requests:
//   structure   FrameBegin/End (one frame is read: the first, or LoadOptions::frame;
//               RibFrames lists them), WorldBegin/End, AttributeBegin/End,
//               TransformBegin/End, ReadArchive (paths relative to the including file),
//               Procedural "DelayedReadArchive", ObjectBegin/End and ObjectInstance
//   camera      Format, Projection "perspective" ("fov") and "orthographic", ScreenWindow,
//               CropWindow, Clipping, PixelSamples, Display (and its type), and the
//               transformations before WorldBegin (the world-to-camera transformation,
//               camera space left-handed)
//   transforms  Identity, Transform, ConcatTransform, Translate, Rotate, Scale,
//               Orientation, ReverseOrientation, Sides
//   geometry    Basis (by name or by matrix, with step), Patch "bilinear"/"bicubic" and
//               PatchMesh (periodic and nonperiodic) with "P", "Pw" or "Pz", NuPatch with
//               "P" or "Pw", TrimCurve and Attribute "trimcurve" "sense", SubdivisionMesh
//               (with "st" of class vertex, varying or facevarying and its tags),
//               Sphere, Cylinder, Cone, Paraboloid, Hyperboloid, Disk, Torus,
//               Geometry "teapot"; Polygon, GeneralPolygon, PointsPolygons and
//               PointsGeneralPolygons with "P" or "Pw", "N", "Cs" and "st" of any storage
//               class (rib_polygons.cpp), triangulated into the scene's polygons;
//               Curves "linear"/"cubic", periodic or not, with "width" or "constantwidth"
//               (rib_curves.cpp): ribbons facing the camera, a surface per segment
//   appearance  Color, Opacity, Surface "constant"/"matte"/"plastic"/"metal"/
//               "paintedplastic"/"shinymetal", Displacement "bumpy" (a bump map),
//               LightSource "ambientlight"/"distantlight"/"pointlight"/"spotlight" and
//               "shadowspot"/"shadowdistant"/"shadowpoint", MakeShadow,
//               MakeLatLongEnvironment, MakeCubeFaceEnvironment
// Every other request is read and skipped with one warning per kind naming file:line and
// counting how often it came. Malformed input (unbalanced blocks, wrong argument counts or
// array lengths, unknown bases, truncated files, bad numbers) is an error naming
// file:line. Inside WorldBegin a Transform sets the object-to-world transformation.
#pragma once

#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "scene/scene.h"

namespace patchscan {

// Reads a .rib file (and the archives it reads). Never throws on bad input; memory grows
// with the text, never with a count the text claims.
std::variant<Scene, SourceError> ReadRib(const std::string& path, const LoadOptions& options = {});

// Parses RIB text; `name` names it in messages and anchors relative archive paths.
std::variant<Scene, SourceError> ParseRib(std::string_view text, const std::string& name,
                                          const LoadOptions& options = {});

// A frame of a RIB file: its FrameBegin number, the file its Display (the last in the
// frame, else the last before it) names, and whether that is a depth map ("zfile" or
// "shadow") rather than a picture. Display requests inside ReadArchive files are not seen.
struct RibFrame {
  int number = 0;
  bool depthMap = false;
  std::string display;  // as written ("" when no Display names a file)
};

// The frames of the .rib file at `path`, in order: empty when it has none or cannot be
// read (ReadRib says why).
std::vector<RibFrame> RibFrames(const std::string& path);

// The Utah teapot as RenderMan's Geometry "teapot" makes it: 32 bicubic Bézier patches,
// z up, its base on z = 0 (the same data as surfaces/teapot.bpt).
std::string_view TeapotBptText();

}  // namespace patchscan

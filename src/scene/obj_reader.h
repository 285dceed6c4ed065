// Wavefront .obj files read as subdivision cages: every face of the
// file is a base face of one cage, subdivided by the scheme asked (Catmull-Clark by
// default; Loop for a cage of triangles; bilinear renders the cage itself, flat).
//
// Read: `v x y z [w]` (w ignored: it weights rational curves, not polygons), `f` with n
// vertices as `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative (relative to the
// vertices read so far), and the tag lines of OpenSubdiv's shape files,
// `t name nint/nfloat/nstring ints... floats... strings...`, with indices from 0:
//   t crease n/1/0 v0 .. v(n-1) s       a chain of edges, all of sharpness s
//   t crease n/(n-1)/0 v0 .. s0 ..      or one sharpness per edge
//   t corner n/1/0 v.. s  (or n/n/0)    vertices of sharpness s (10 or more: infinite)
//   t hole n/0/0 f..                    faces not rendered
//   t interpolateboundary 1/0/0 k       RenderMan's 0, 1 or 2; by default 1 here (a
//                                       modelling tool shows a cage's boundary; RenderMan's
//                                       own default, 0, drops the boundary faces)
//   t facevaryinginterpolateboundary 1/0/0 k   OpenSubdiv's face-varying rule 0-5
//                                       (FaceVaryingRule's order); by default 1, corners kept
// `vt u v` are the face-varying texture coordinates "st" = (u, 1 - v) (OBJ's v runs up the
// image) when every face gives them (`v/vt`); if some faces do and others do not, they are
// not applied and a warning says so. `vn` are counted and their indices checked; their
// values are not used (the limit surface's normal is exact). `g`, `o`, `s`, `usemtl` and
// `mtllib` are ignored; any other statement is skipped with one warning per kind giving its
// first line and count.
//
// Errors name file:line: a number that is not one, an index of 0 or out of range, a face of
// fewer than 3 vertices or using a vertex twice, a Loop face that is not a triangle, a tag
// with the wrong counts or an index out of range; and at the first face's line, a cage
// that is not a manifold (PrepareSubdivFaces: an edge of three faces, orientations that
// disagree, a bowtie vertex, a crease off the edges). Vertices at the same position are
// distinct vertices (the cage is open there, as the file says).
#pragma once

#include <string>
#include <string_view>
#include <variant>

#include "scene/scene.h"

namespace patchscan {

struct ObjOptions {
  SubdivScheme scheme = SubdivScheme::CatmullClark;
};

std::variant<Scene, SourceError> ReadObj(const std::string& path, const ObjOptions& options = {});
// The same, from text in memory (`name` for messages).
std::variant<Scene, SourceError> ParseObj(std::string_view text, const std::string& name, const ObjOptions& options = {});

}  // namespace patchscan

// CAD models read through Open CASCADE Technology: STEP (.step, .stp: AP203, AP214, AP242
// B-rep), IGES (.iges, .igs) and OCCT's own .brep. Every B-rep face becomes trimmed
// surfaces (scene/cad_face.h) that the scans render directly: planes and quadrics as their
// analytic shapes, B-splines as NURBS, swept and offset surfaces made B-splines first.
//
// STEP and IGES go through OCCT's XDE document: an assembly's parts are instances of one
// prepared shape each (a part placed five times is converted once), and a face takes the
// colour XDE gives it, else its solid's or part's, else its instance's, else the renderer's
// default material. Coordinates are OCCT's: millimetres.
//
// Errors name the file: one that cannot be read or parsed, a STEP with no B-rep (AP242
// tessellated-only files give OCCT a null shape). A face that cannot be converted (no
// B-spline, no pcurves, wires that do not close) is skipped, counted in a warning naming
// its number and reason.
//
// The program reads CAD files through patchscan-cad.so (scene/cad_library.h), which this
// reader is built into; it links Open CASCADE itself.
#pragma once

#include <string>
#include <variant>

#include "scene/cad_library.h"
#include "scene/scene.h"

namespace patchscan {

// asNurbs: every face as trimmed NURBS (LoadOptions::cadAsNurbs).
std::variant<Scene, SourceError> ReadCad(const std::string& path, bool asNurbs = false);

}  // namespace patchscan

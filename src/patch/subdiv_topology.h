// A subdivision cage's topology as OpenSubdiv's Far builds it (patch/subdiv.h): the cage
// checked for what OpenSubdiv cannot be trusted to refuse, RenderMan's rules and tags
// (RenderMan Interface 3.2, SubdivisionMesh) given to Far, and the questions about a face's
// neighbourhood that decide how it is evaluated.
#pragma once

#include <opensubdiv/far/topologyLevel.h>
#include <opensubdiv/far/topologyRefiner.h>

#include <memory>
#include <optional>
#include <vector>

#include "patch/subdiv.h"

namespace patchscan {

// OpenSubdiv's error and warning callbacks silenced, once per program.
void QuietOpenSubdiv();

// Checks `mesh` and builds its OpenSubdiv topology, with RenderMan's boundary rule and the
// texture coordinates' channel. Throws std::invalid_argument naming what is wrong.
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> BuildRefiner(const SubdivMesh& mesh);

// The control points of a Catmull-Clark quadrilateral whose limit surface is the uniform
// bicubic B-spline patch of its 16 neighbouring points, or nothing (see the definition).
std::optional<std::vector<int>> RegularNeighbourhood(const OpenSubdiv::Far::TopologyLevel& level, int face);

// Whether base vertex v is an extraordinary point of the Catmull-Clark limit surface.
bool SmoothExtraordinary(const OpenSubdiv::Far::TopologyLevel& level, int v);

}  // namespace patchscan

// The pipeline as one call: a scene file rendered to an image file, frame by frame. Each
// frame is read (render/load.h), its front end made (the direct scan or the tessellated
// mesh), its back end set up (render/back_end.h), and its rows rendered and streamed to
// the image, which is written whole or not at all.
#pragma once

#include <functional>
#include <iosfwd>
#include <optional>
#include <set>
#include <string>

#include "render/options.h"
#include "render/report.h"
#include "render/status.h"

namespace patchscan::render {

// Renders one frame of o.file (its first, or o.camera.frame) to o.output, else the
// scene's Display, else <stem>.png in the current directory (which `log` is told).
// Warnings and the progress line go to `log`; `warned`: warnings given already (by
// earlier frames), not given again. Failure: BadOption for options that do not fit the
// scene or each other, InputError for the scene or what it names, OutputError for the
// image, Interrupted once render::gInterrupted is set.
Result<RenderReport> RenderFrame(const RenderOptions& o, std::ostream& log, std::set<std::string>* warned = nullptr);

// Called after each frame with what it took; a failure stops the frames.
using FrameDone = std::function<std::optional<Failure>(const RenderReport&)>;

// Renders o.file. A RIB file of several frames: every frame in order, or o.frames (or the
// one frame o.camera.frame), each to its Display, except that o.output, when given, takes
// the place of the last frame's that writes a picture (not a depth map). Any other file:
// its one frame. Returns the first failure, if any.
std::optional<Failure> RenderFile(const RenderOptions& o, std::ostream& log, const FrameDone& done);

}  // namespace patchscan::render

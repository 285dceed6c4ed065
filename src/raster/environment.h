// Environment mapping (Blinn and Newell, "Texture and Reflection in Computer Generated
// Images", CACM 1976): a mirror-like surface shows what lies in the direction the view
// reflects to, looked up in an image of the surroundings at infinity. The lookup is filtered
// over the reflected direction's change per pixel, as a texture over its footprint; here
// that change is the view direction's across the pixel reflected in the point's tangent
// plane (a flat mirror's footprint): the turning of a curved mirror's normal across the pixel
// is not known to a shading point, and the supersampling grid filters what it adds.
#pragma once

#include "raster/bump.h"
#include "raster/mesh.h"

namespace patchscan::raster {

class ImageTexture;

// A material's environment: the map (not owned; none: no reflection) and Kr, the share of
// it reflected (times the colour the material's highlights take).
struct EnvironmentMap {
  ImageTexture* map = nullptr;
  double kr = 1.0;
};

// The view direction from `eye` reflected at p in the plane of normal n (any length, either
// side), and its change per pixel in screen x and y (the view direction's, reflected).
struct Reflection {
  Vec3 r, drdx, drdy;
};
Reflection ReflectedView(const ScreenRows& screen, const Vec3& p, const Vec3& n, const Vec3& eye, bool orthographic);

}  // namespace patchscan::raster

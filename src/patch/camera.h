// The perspective camera and the screen space it defines.
// Screen space: x right and y down in pixels (pixel (i, j) covers [i, i+1) x [j, j+1)),
// and depth = 1 - hither / z, with z the distance along the view axis: depth is linear in
// 1/z, 0 on the hither plane, approaching 1 at infinity, negative between eye and hither.
#pragma once

#include <optional>
#include <string>

#include "patch/geometry.h"

namespace patchscan {

struct Camera {
  int width = 640, height = 480;
  Vec3 eye = Vec3(0, -10, 0), lookAt = Vec3(0, 0, 0), up = Vec3(0, 0, 1);
  double fovDeg = 30.0;  // vertical field of view
  double hither = 0.01;  // distance of the hither (near) plane from the eye, > 0

  // A RenderMan camera (RenderMan Interface 3.2, "Camera"), from a scene file. When set,
  // eye, lookAt, up and fovDeg are ignored: `cameraFromWorld` maps world points into camera
  // space (x right, y up, z forward: left-handed for a rotation), and the image spans the
  // screen window (left, right, bottom, top) on the plane z = 1 (perspective: the window
  // of Projection and ScreenWindow scaled by tan(fov/2)). hither is a camera-space z.
  // orthographic (RenderMan's Projection "orthographic"): the window is on every plane
  // z = const and view rays are parallel to the z axis.
  std::optional<Mat4> cameraFromWorld;
  Vec4 screenWindow = Vec4(-1, 1, -1, 1);
  bool orthographic = false;
};

// The eye's world position, the world direction of the image's x axis (to the right) and
// of the view axis (forward), for either kind of camera. Precondition: a valid camera.
Vec3 EyePoint(const Camera& c);
Vec3 ViewRight(const Camera& c);
Vec3 ViewForward(const Camera& c);

// The row r with r . (p, 1) the distance of world point p along the view axis from the
// eye (perspective) or the camera plane (orthographic): what the back end calls w.
Vec4 ViewDepthRow(const Camera& c);

// Limits that keep the arithmetic of a camera meaningful.
constexpr int kMaxImageSide = 1 << 16;   // pixel indices stay exact in int and float
constexpr double kMinFovDeg = 1e-6;      // a narrower cone has a focal length beyond 1e11 px
constexpr double kMaxFovDeg = 179.0;     // tan(fov/2) must stay finite
constexpr double kMinUpSine = 1e-9;      // |up x view| below this: up is along the view

// nullopt when the camera is usable; otherwise what is wrong with it, for the user.
std::optional<std::string> ValidateCamera(const Camera& c);

// The projective map from world space to homogeneous screen space (X, Y, D, W):
// x = X/W, y = Y/W, depth = D/W. In perspective W is the distance along the view axis and
// depth = 1 - hither / W; orthographic cameras have W = 1 and depth = distance - hither.
// Precondition: ValidateCamera(c) is nullopt.
Mat4 ScreenFromWorld(const Camera& c);

// The focal length in pixels: (height / 2) / tan(fov / 2).
double FocalPixels(const Camera& c);

// The default direction from the scene towards the eye for automatic framing: in front,
// a little to the right and above, relative to `up` (front is -y for a z-up scene and +z
// for a y-up scene).
Vec3 DefaultViewDirection(const Vec3& up);

// A camera that looks at the centre of `world` from `direction` (towards the eye) at the
// nearest distance where all eight corners of the box fall inside the image with a margin.
// Keeps width, height, fov and up of `base`; sets eye, lookAt and hither.
Camera FrameBounds(const Bounds3& world, const Camera& base, const Vec3& direction);

}  // namespace patchscan

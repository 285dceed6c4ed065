#include "patch/camera.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace patchscan {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
// The framed box's corners fill at most this fraction of the image's half-width and
// half-height: a margin around the scene.
constexpr double kFrameFill = 0.9;
// The hither plane of a framed camera, as a fraction of the depth of the box's nearest
// corner: near enough never to clip the scene, far enough to keep 1/z well scaled.
constexpr double kFrameHitherFraction = 0.5;

struct ViewFrame {
  Vec3 right, down, forward;
};

ViewFrame Frame(const Camera& c) {
  const Vec3 forward = (c.lookAt - c.eye).normalized();
  const Vec3 right = forward.cross(c.up).normalized();
  return {right, forward.cross(right), forward};
}

}  // namespace

namespace {

// What is wrong with the camera's own view (a RenderMan matrix and window, or eye, look-at,
// up and field of view), written to `why`; nothing when it is usable.
void ValidateView(const Camera& c, std::ostream& why) {
  if (c.cameraFromWorld) {
    const Mat4& m = *c.cameraFromWorld;
    const Vec4& win = c.screenWindow;
    // The linear part must be invertible relative to its own scale for the eye and the
    // view axes to exist.
    const double scale = m.block<3, 3>(0, 0).cwiseAbs().maxCoeff();
    if (!m.allFinite() || m.row(3) != Vec4(0, 0, 0, 1).transpose())
      why << "the camera transformation must be finite and affine";
    else if (!(std::abs(m.block<3, 3>(0, 0).determinant()) > 1e-12 * scale * scale * scale))
      why << "the camera transformation is singular";
    else if (!win.allFinite() || win[0] == win[1] || win[2] == win[3])
      why << "the screen window is empty or not finite";
    return;
  }
  if (!c.eye.allFinite() || !c.lookAt.allFinite() || !c.up.allFinite())
    why << "eye, look-at and up must be finite";
  else if (!(c.fovDeg >= kMinFovDeg && c.fovDeg <= kMaxFovDeg))
    why << "field of view " << c.fovDeg << " degrees is outside " << kMinFovDeg << " to "
        << kMaxFovDeg;
  else if ((c.lookAt - c.eye).norm() == 0.0)
    why << "eye and look-at are the same point";
  else if (c.up.norm() == 0.0 ||
           (c.lookAt - c.eye).normalized().cross(c.up.normalized()).norm() < kMinUpSine)
    why << "up vector is zero or along the view direction";
}

}  // namespace

std::optional<std::string> ValidateCamera(const Camera& c) {
  std::ostringstream why;
  if (c.width < 1 || c.height < 1 || c.width > kMaxImageSide || c.height > kMaxImageSide)
    why << "image size " << c.width << "x" << c.height << " is outside 1x1 to " << kMaxImageSide
        << "x" << kMaxImageSide;
  else
    ValidateView(c, why);
  if (why.tellp() == 0 && (!(c.hither > 0.0) || !std::isfinite(c.hither)))
    why << "hither distance must be positive and finite";
  if (why.tellp() == 0) return std::nullopt;
  return why.str();
}

double FocalPixels(const Camera& c) {
  return 0.5 * c.height / std::tan(0.5 * c.fovDeg * kRadPerDeg);
}

Vec3 EyePoint(const Camera& c) {
  if (!c.cameraFromWorld) return c.eye;
  const Mat4& m = *c.cameraFromWorld;
  return m.block<3, 3>(0, 0).inverse() * -m.block<3, 1>(0, 3);
}

Vec3 ViewRight(const Camera& c) {
  if (!c.cameraFromWorld) return Frame(c).right;
  return (c.cameraFromWorld->block<3, 3>(0, 0).inverse() * Vec3(1, 0, 0)).normalized();
}

Vec3 ViewForward(const Camera& c) {
  if (!c.cameraFromWorld) return Frame(c).forward;
  // The world direction whose camera-space image has no x or y: the view axis.
  return (c.cameraFromWorld->block<3, 3>(0, 0).inverse() * Vec3(0, 0, 1)).normalized();
}

Vec4 ViewDepthRow(const Camera& c) {
  if (c.cameraFromWorld) return c.cameraFromWorld->row(2).transpose();
  return ScreenFromWorld(c).row(3).transpose();
}

Mat4 ScreenFromWorld(const Camera& c) {
  if (c.cameraFromWorld) {
    // Camera space (x, y, z) to pixels: x_px = W (x/z - l) / (r - l), y_px = H (t - y/z) /
    // (t - b), depth = 1 - hither / z, w = z.
    const double l = c.screenWindow[0], r = c.screenWindow[1], b = c.screenWindow[2],
                 t = c.screenWindow[3];
    const double sx = c.width / (r - l), sy = c.height / (t - b);
    Mat4 p = Mat4::Zero();
    if (c.orthographic) {
      // x_px = W (x - l) / (r - l), y_px = H (t - y) / (t - b), depth = z - hither, w = 1.
      p.row(0) << sx, 0, 0, -sx * l;
      p.row(1) << 0, -sy, 0, sy * t;
      p.row(2) << 0, 0, 1, -c.hither;
      p.row(3) << 0, 0, 0, 1;
      return p * *c.cameraFromWorld;
    }
    p.row(0) << sx, 0, -sx * l, 0;
    p.row(1) << 0, -sy, sy * t, 0;
    p.row(2) << 0, 0, 1, -c.hither;
    p.row(3) << 0, 0, 1, 0;
    return p * *c.cameraFromWorld;
  }
  const ViewFrame f = Frame(c);
  const double focal = FocalPixels(c), cx = 0.5 * c.width, cy = 0.5 * c.height;
  // Rows applied to (p - eye): X = focal * right + cx * forward, Y = focal * down +
  // cy * forward, D = forward - hither, W = forward.
  Mat4 m = Mat4::Zero();
  m.block<1, 3>(0, 0) = (focal * f.right + cx * f.forward).transpose();
  m.block<1, 3>(1, 0) = (focal * f.down + cy * f.forward).transpose();
  m.block<1, 3>(2, 0) = f.forward.transpose();
  m.block<1, 3>(3, 0) = f.forward.transpose();
  m.block<4, 1>(0, 3) = -m.block<4, 3>(0, 0) * c.eye;
  m(2, 3) -= c.hither;
  return m;
}

Vec3 DefaultViewDirection(const Vec3& up) {
  const Vec3 u = up.normalized();
  // Front: -y, unless up is close to the y axis, then +z.
  Vec3 front = std::abs(u.y()) < 0.9 ? Vec3(0, -1, 0) : Vec3(0, 0, 1);
  front = (front - front.dot(u) * u).normalized();
  const Vec3 right = (-front).cross(u);  // the screen's right when looking along -front
  return (front + 0.45 * right + 0.55 * u).normalized();
}

Camera FrameBounds(const Bounds3& world, const Camera& base, const Vec3& direction) {
  Camera c = base;
  Bounds3 box = world;
  if (box.Empty()) box.Extend(Vec3::Zero());
  const Vec3 centre = box.Centre();
  // A point-like scene still gets a camera: give the box a size relative to its place.
  const double floor = 1e-9 * std::max(centre.cwiseAbs().maxCoeff(), 1e-300);
  if (box.Diagonal().maxCoeff() < floor) {
    box.Extend(centre + Vec3::Constant(floor));
    box.Extend(centre - Vec3::Constant(floor));
  }
  c.lookAt = centre;
  c.eye = centre + direction.normalized();  // provisional, for the view frame
  const ViewFrame f = Frame(c);
  // The eye sits at distance D from the centre, back along `forward`. A corner q (relative
  // to the centre) is at depth D + q.forward and must satisfy |q.right| <= tanH * fill *
  // depth and |q.down| <= tanV * fill * depth: each corner bounds D from below.
  const double tanV = std::tan(0.5 * c.fovDeg * kRadPerDeg);
  const double tanH = tanV * c.width / c.height;
  double dist = 0.0, nearest = INFINITY;
  const BoxHull corners = BoxCorners(box);
  for (const Vec3& corner : corners) {
    const Vec3 q = corner - centre;
    const double depthOffset = q.dot(f.forward);
    dist = std::max({dist, std::abs(q.dot(f.right)) / (kFrameFill * tanH) - depthOffset,
                     std::abs(q.dot(f.down)) / (kFrameFill * tanV) - depthOffset,
                     -depthOffset + box.Diagonal().norm() * 1e-3});
  }
  for (const Vec3& corner : corners) nearest = std::min(nearest, dist + (corner - centre).dot(f.forward));
  c.eye = centre - f.forward * dist;
  c.hither = kFrameHitherFraction * nearest;
  return c;
}

}  // namespace patchscan

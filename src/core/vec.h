// The vector vocabulary of every layer: one name per shape, all double (STYLE.md: double
// for all geometry and numerics). A 2-vector is a Vec2 whatever it holds: (u,v), screen
// (x,y), a gradient or a pair of residuals.
#pragma once

#include <Eigen/Core>

namespace patchscan {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec4 = Eigen::Vector4d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;

}  // namespace patchscan

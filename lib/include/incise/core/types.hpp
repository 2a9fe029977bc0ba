#pragma once
/// \file types.hpp
/// Scalar, index and small fixed-size vector types shared by every module.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace incise {

/// Index of a node, element or degree of freedom. 32 bits: meshes up to 2^31 entities.
using Index = std::int32_t;

/// Floating-point type of every stored quantity (SI units throughout).
using Real = double;

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;

}  // namespace incise

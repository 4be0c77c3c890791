/* imm-monoslam — fixed-size Eigen aliases of the uncertain projective geometry module. */
#pragma once

#include <immslam/math/types.h>

#include <Eigen/Geometry>  // cross products

namespace immslam::geometry
{
/** 4x6: Jacobian of a homogeneous 4-vector (point or plane) w.r.t. a Plücker 6-vector. */
using Mat46 = Eigen::Matrix<double, 4, 6>;
/** 6x4: Jacobian of a Plücker 6-vector w.r.t. a homogeneous 4-vector (point or plane). */
using Mat64 = Eigen::Matrix<double, 6, 4>;
/** 1x4 and 1x6 row Jacobians of scalar relations. */
using Mat14 = Eigen::Matrix<double, 1, 4>;
using Mat16 = Eigen::Matrix<double, 1, 6>;
}  // namespace immslam::geometry

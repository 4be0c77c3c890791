/* imm-monoslam — spherical normalization of homogeneous vectors (Heuel 2004, sec. 2.2.1). */
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <stdexcept>

namespace immslam::geometry
{
/** Spherical normalization \f$ x_s = x / |x| \f$ of a homogeneous vector (point, plane or Plücker
 * line), Heuel's practice to keep the numbers of uncertain projective entities well conditioned.
 * \param J_xs_x optional Jacobian \f$ \partial x_s / \partial x = (I - x_s x_s^\top)/|x| \f$, used to
 *        propagate the covariance: \f$ \Sigma_{x_s x_s} = J \Sigma_{xx} J^\top \f$ (its null space
 *        then contains \f$ x_s \f$: the scale of a homogeneous vector carries no information).
 * \throws std::runtime_error if x is zero or not finite. */
template <int N>
Eigen::Matrix<double, N, 1> sphericallyNormalized(const Eigen::Matrix<double, N, 1>& x,
                                                  Eigen::Matrix<double, N, N>* J_xs_x = nullptr)
{
  const double n = x.norm();
  if (!(n > 0) || !std::isfinite(n))
    throw std::runtime_error(
        "immslam/geometry/spherical_normalization.h: sphericallyNormalized of a zero or non-finite "
        "homogeneous vector");
  const Eigen::Matrix<double, N, 1> xs = x / n;
  if (J_xs_x)
    *J_xs_x = (Eigen::Matrix<double, N, N>::Identity() - xs * xs.transpose()) / n;
  return xs;
}
}  // namespace immslam::geometry

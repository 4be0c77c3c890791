/* imm-monoslam — closed-form similarity alignment of point sets (Umeyama 1991). */
#pragma once

#include <immslam/math/types.h>

#include <vector>

namespace immslam::eval
{
/** Which transform aligns an estimate to ground truth before errors are measured. */
enum class EAlignment
{
  Sim3,  ///< rotation, translation and scale (monocular: scale is unobservable)
  SE3,   ///< rotation and translation, scale fixed to 1
  None   ///< no alignment: errors in the estimate's own frame
};

/** Readable name of an alignment ("Sim3", "SE3", "None"). */
const char* alignmentName(EAlignment a);

/** A similarity transform x -> s R x + t (s > 0 except in the documented degenerate cases). */
struct TSim3
{
  double s = 1.0;               ///< scale
  Mat3 R = Mat3::Identity();    ///< proper rotation (det = +1)
  Vec3 t = Vec3::Zero();        ///< translation

  /** s R x + t. */
  Vec3 transform(const Vec3& x) const { return s * (R * x) + t; }
  /** The inverse x -> R^T (x - t) / s (requires s != 0). */
  TSim3 inverse() const;
  /** Composition: (this * other)(x) = this(other(x)). */
  TSim3 operator*(const TSim3& other) const;
};

/** Least-squares similarity (Umeyama, IEEE TPAMI 13(4), 1991, eqs. 40-42) aligning src to dst:
 * minimizes \f$ \sum_i \| d_i - (s R s_i + t) \|^2 \f$ over proper rotations R, s (or s = 1 when
 * withScale is false) and t.
 *
 * With centroids \f$\mu_s, \mu_d\f$, \f$\sigma_s^2 = \frac1n\sum\|s_i-\mu_s\|^2\f$ and the
 * cross-covariance \f$\Sigma = \frac1n \sum (d_i-\mu_d)(s_i-\mu_s)^\top = U D V^\top\f$:
 * \f$ R = U S V^\top \f$ with \f$ S = \mathrm{diag}(1, 1, \det U \det V) \f$,
 * \f$ s = \mathrm{tr}(D S)/\sigma_s^2 \f$, \f$ t = \mu_d - s R \mu_s \f$.
 *
 * Degenerate inputs (never NaN, never throws for them):
 * - no points: the identity (s = 1, R = I, t = 0);
 * - rank 0, i.e. all src points identical, all dst points identical (up to 1e-12 relative
 *   rounding), a single point, or an uncorrelated cross-covariance: translation only,
 *   s = 1, R = I, t = mu_d - mu_s (for identical dst the least-squares scale would be 0);
 * - rank 1 (collinear points, e.g. two points): the rotation about the line is free; returned is
 *   the smallest rotation taking the src line direction onto the dst one, which is optimal,
 *   with s and t from the formulas above;
 * - rank 2 (coplanar points, e.g. a planar trajectory) is fully determined and handled by the
 *   general formula.
 * \param rank optional output: the rank (0..3) of the cross-covariance as used above.
 * \throws std::invalid_argument if the sizes differ or a coordinate is not finite. */
TSim3 alignUmeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst, bool withScale,
                   int* rank = nullptr);
}  // namespace immslam::eval

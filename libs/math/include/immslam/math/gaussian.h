/* imm-monoslam — Gaussian likelihoods computed stably in log space. */
#pragma once

#include <immslam/math/types.h>

namespace immslam::math
{
/** Log of the Gaussian density N(nu; 0, S) (IMM paper eq. 3):
 * \f$ -\tfrac12 (\nu^\top S^{-1}\nu + \ln|S| + m \ln 2\pi) \f$, via a Cholesky factor of S.
 * \param mahalanobis2 optional output: \f$ \nu^\top S^{-1}\nu \f$.
 * \return -infinity if S is not positive definite. */
double gaussianLogLikelihood(const VecX& nu, const MatX& S, double* mahalanobis2 = nullptr);

/** Squared Mahalanobis distance \f$ \nu^\top S^{-1}\nu \f$ (infinity if S is not PD). */
double mahalanobis2(const VecX& nu, const MatX& S);

/** log(sum(exp(v))) without overflow. */
double logSumExp(const VecX& v);

/** Forces a square matrix to be exactly symmetric: P = (P + P^T)/2. */
void symmetrize(MatX& P);
}  // namespace immslam::math

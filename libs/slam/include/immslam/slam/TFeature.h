/* imm-monoslam — bookkeeping of one map feature of the SLAM state (the layout shared by every
 * mode of the IMM bank). */
#pragma once

#include <immslam/math/types.h>

#include <cstdint>

namespace immslam::slam
{
/** Parametrization of a feature in the state. */
enum class EFeatureKind : std::uint8_t
{
  InverseDepth,  ///< 6-D (x0 y0 z0 theta phi rho), features/inverse_depth.h
  XYZ            ///< 3-D Euclidean point in W
};

/** Size of a feature's block in the state vector. */
constexpr int featureDim(EFeatureKind k) { return k == EFeatureKind::InverseDepth ? 6 : 3; }

/** One map feature: where its block lives in the state and its track record. Its appearance (the
 * template) is image work and lives with the tracker (CSlamTracker), keyed by id. */
struct TFeature
{
  std::int64_t id = -1;
  EFeatureKind kind = EFeatureKind::InverseDepth;
  int offset = 0;  ///< index of the first element of its block in the state vector (every mode)

  Vec3 r0 = Vec3::Zero();         ///< camera centre T_W_C at its first observation (patch warping)
  Vec4 q0 = Vec4(1, 0, 0, 0);     ///< camera orientation at its first observation

  double tInit = 0;           ///< timestamp of the first observation
  std::int64_t frameInit = 0; ///< frame number of the first observation
  int nPredicted = 0;         ///< frames it was predicted inside the image and searched
  int nMatched = 0;           ///< frames its measurement was used in the update
  std::int64_t lastSeenFrame = 0;  ///< last frame it was predicted inside the image
  int rejectedInRow = 0;      ///< consecutive frames it was found but rejected as an outlier
  std::int64_t lastFoundFrame = -1;  ///< last frame its search found a match (used or rejected)
  double tLastInlier = 0;             ///< timestamp of the last frame its measurement was used
  Vec2 uvLastInlier = Vec2::Zero();   ///< the pixel measured then

  int dim() const { return featureDim(kind); }
};
}  // namespace immslam::slam

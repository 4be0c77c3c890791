/* imm-monoslam — relative pose error. */
#include <immslam/eval/associate.h>
#include <immslam/eval/ate.h>
#include <immslam/eval/rpe.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/quaternion.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace immslam::eval
{
TRpeResult computeRpe(const core::TTrajectory& est, const core::TTrajectory& gt, int delta, EAlignment a,
                      double maxDt)
{
  if (delta < 1) throw std::invalid_argument("computeRpe: delta must be >= 1");
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  auto pairs = associateByTimestamp(est, gt, maxDt);
  if (pairs.size() < static_cast<size_t>(delta) + 1)
    throw std::runtime_error("computeRpe: " + std::to_string(pairs.size()) +
                             " associated poses, need at least delta + 1 = " + std::to_string(delta + 1));
  std::sort(pairs.begin(), pairs.end(), [&](const auto& x, const auto& y) {
    return std::make_pair(gt[x.second].timestamp, x.second) < std::make_pair(gt[y.second].timestamp, y.second);
  });
  TRpeResult r;
  r.delta = delta;
  r.scale = a == EAlignment::Sim3 ? alignTrajectories(est, gt, pairs, EAlignment::Sim3).s : 1.0;

  std::vector<double> tr, rot, gtLen;
  for (size_t k = 0; k + static_cast<size_t>(delta) < pairs.size(); ++k)
    gtLen.push_back((gt[pairs[k + static_cast<size_t>(delta)].second].p_W_C - gt[pairs[k].second].p_W_C).norm());
  r.minMotion = 0.1 * median(gtLen);
  std::vector<double> dir, ratio;
  for (size_t k = 0; k + static_cast<size_t>(delta) < pairs.size(); ++k)
  {
    const auto& e0 = est[pairs[k].first];
    const auto& e1 = est[pairs[k + static_cast<size_t>(delta)].first];
    const auto& g0 = gt[pairs[k].second];
    const auto& g1 = gt[pairs[k + static_cast<size_t>(delta)].second];
    // Relative motions expressed in the first pose's frame: dp = R0^T (p1 - p0), dq = q0^-1 q1.
    const Vec3 dpE = r.scale * math::quatRotate(math::quatConjugate(e0.q_W_C), e1.p_W_C - e0.p_W_C);
    const Vec3 dpG = math::quatRotate(math::quatConjugate(g0.q_W_C), g1.p_W_C - g0.p_W_C);
    const Vec4 dqE = math::quatMultiply(math::quatConjugate(e0.q_W_C), e1.q_W_C);
    const Vec4 dqG = math::quatMultiply(math::quatConjugate(g0.q_W_C), g1.q_W_C);
    // E = dG^-1 dE: its translation dqG^-1 (dpE - dpG) has the norm |dpE - dpG|.
    TRpePairError pe;
    pe.tStart = g0.timestamp;
    pe.tEnd = g1.timestamp;
    pe.translation = (dpE - dpG).norm();
    pe.rotationDeg =
        math::quatToRotationVector(math::quatMultiply(math::quatConjugate(dqG), dqE)).norm() * 180.0 / M_PI;
    const double nE = dpE.norm(), nG = dpG.norm();
    if (nG >= r.minMotion && nG > 0 && nE > 0)
    {
      pe.directionDeg = std::atan2(dpE.cross(dpG).norm(), dpE.dot(dpG)) * 180.0 / M_PI;
      dir.push_back(pe.directionDeg);
      pe.scaleRatio = nE / nG;
      ratio.push_back(pe.scaleRatio);
    }
    else
      pe.directionDeg = pe.scaleRatio = kNaN;
    tr.push_back(pe.translation);
    rot.push_back(pe.rotationDeg);
    r.errors.push_back(pe);
  }
  r.nPairs = r.errors.size();
  r.translationRmse = rms(tr);
  r.translationMean = mean(tr);
  r.translationMedian = median(tr);
  r.translationMax = maxValue(tr);
  r.rotationRmseDeg = rms(rot);
  r.rotationMeanDeg = mean(rot);
  r.rotationMedianDeg = median(rot);
  r.rotationMaxDeg = maxValue(rot);
  r.nDirections = dir.size();
  r.directionMedianDeg = dir.empty() ? kNaN : median(dir);
  r.directionRmseDeg = dir.empty() ? kNaN : rms(dir);
  r.scaleRatioMedian = ratio.empty() ? kNaN : median(ratio);
  r.scaleRatioP10 = ratio.empty() ? kNaN : percentile(ratio, 10);
  r.scaleRatioP90 = ratio.empty() ? kNaN : percentile(ratio, 90);
  std::vector<double> logs;
  for (double x : ratio) logs.push_back(std::log(x));
  r.scaleLogRms = logs.empty() ? kNaN : rms(logs);
  return r;
}
}  // namespace immslam::eval

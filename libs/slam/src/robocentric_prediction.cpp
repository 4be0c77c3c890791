/* imm-monoslam — camera-centred prediction: compose the whole state with the camera increment. */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/robocentric_prediction.h>

#include <Eigen/Cholesky>
#include <stdexcept>

namespace immslam::slam
{
namespace
{
constexpr int kU = motion::kV;  // velocities u = (v, w) at 7..12

using TBlockJac = TTransitionBlock;
/** Rows of block a of M = A P~ in the columns of block b: M(a, b) = D_a P~(a, b) + G_a P~(u, b). */
template <int Sa, int Sb>
void panelRows(const TBlockJac& a, const MatX& P, const Eigen::Matrix<double, 6, Sb>& Pub, Eigen::Index bOff,
               Eigen::Ref<MatX> panel)
{
  const Eigen::Matrix<double, Sa, Sa> D = a.D.topLeftCorner<Sa, Sa>();
  auto out = panel.block<Sa, Sb>(a.off - bOff, 0);
  out.noalias() = D * P.block<Sa, Sb>(a.off, bOff);
  if (a.hasG) out.noalias() += a.G.topRows<Sa>() * Pub;
}

/** Column block b of P' = M A^T, rows from the block down (lower triangle):
 *  P'(b.., b) = M(b.., b) D_b^T + M(b.., u) G_b^T. M(b.., b) needs P~ only in block b's own columns
 *  (rows from b down, and the rows of u), so the column blocks are independent once M(:, u) is known. */
template <int Sb>
void columnBlock(const TBlockJac& b, const std::vector<TBlockJac>& blocks, const Eigen::Ref<const MatX>& Mu, MatX& P,
                 Eigen::Ref<MatX> panel)
{
  const Eigen::Index h = P.rows() - b.off;
  const Eigen::Matrix<double, 6, Sb> Pub = P.block<6, Sb>(kU, b.off);
  for (const auto& a : blocks)
  {
    if (a.off < b.off) continue;
    switch (a.len)
    {
      case 3: panelRows<3, Sb>(a, P, Pub, b.off, panel); break;
      case 6: panelRows<6, Sb>(a, P, Pub, b.off, panel); break;
      default: panelRows<7, Sb>(a, P, Pub, b.off, panel); break;
    }
  }
  const Eigen::Matrix<double, Sb, Sb> Dt = b.D.topLeftCorner<Sb, Sb>().transpose();
  auto Pc = P.block(b.off, b.off, h, Sb);
  Pc.noalias() = panel.topLeftCorner(h, Sb).lazyProduct(Dt);
  if (b.hasG)
  {
    const Eigen::Matrix<double, 6, Sb> Gt = b.G.topRows<Sb>().transpose();
    Pc.noalias() += Mu.bottomRows(h).lazyProduct(Gt);
  }
}

/** n x 6 factor L with L L^T = B N B^T, B = df/dn: a zero-mean jitter n of the camera (covariance N),
 * applied at the identity increment to the state g (the world pose and every feature are
 * re-expressed through the jitter rotation). */
MatX cameraJitterFactor(const bayes::TGaussian& g, const std::vector<TFeature>& features, const Mat6& noiseCov,
                        const motion::Mat36u& J_t_n, const motion::Mat46u& J_dq_n, int nClones)
{
  const Eigen::Index n = g.x.size();
  MatX B = MatX::Zero(n, 6);
  const Vec3 t0 = Vec3::Zero();
  const Vec4 dq0(1, 0, 0, 0);
  // The world pose and every pose clone are re-expressed alike (T_C'X = T_C'C T_CX).
  for (int c = -1; c < nClones; ++c)
  {
    const int off = c < 0 ? 0 : poseCloneOffset(c);
    Mat3 J_t;
    Mat34 J_dq;
    features::transformPoint(g.x.segment<3>(off), dq0, t0, nullptr, &J_t, &J_dq);
    Mat4 J_cq;
    math::quatMultiply(dq0, g.x.segment<4>(off + 3), &J_cq, nullptr);
    B.middleRows<3>(off) = J_t * J_t_n + J_dq * J_dq_n;
    B.middleRows<4>(off + 3) = J_cq * Vec4(1, -1, -1, -1).asDiagonal() * J_dq_n;
  }
  for (const auto& f : features)
  {
    if (f.kind == EFeatureKind::InverseDepth)
    {
      Eigen::Matrix<double, 6, 3> J_t;
      Eigen::Matrix<double, 6, 4> J_dq;
      features::transformInverseDepth(g.x.segment<6>(f.offset), dq0, t0, nullptr, &J_t, &J_dq);
      B.middleRows<6>(f.offset) = J_t * J_t_n + J_dq * J_dq_n;
    }
    else
    {
      Mat3 J_t;
      Mat34 J_dq;
      features::transformPoint(g.x.segment<3>(f.offset), dq0, t0, nullptr, &J_t, &J_dq);
      B.middleRows<3>(f.offset) = J_t * J_t_n + J_dq * J_dq_n;
    }
  }
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(noiseCov + 1e-30 * Eigen::Matrix<double, 6, 6>::Identity());
  return B * llt.matrixL().toDenseMatrix();
}
}  // namespace

void addCovarianceFactor(MatX& P, const MatX& F)
{
  P.selfadjointView<Eigen::Lower>().rankUpdate(F, 1.0);
  P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
}

MatX shakeFactor(const bayes::TGaussian& g, const std::vector<TFeature>& features, const Mat3& shakeCov, int nClones)
{
  // The shake is a rotation exp(s) of the camera after the motion: d exp(s)/ds = 0.5 [0; I] at s = 0.
  Mat6 N = Mat6::Zero();
  N.bottomRightCorner<3, 3>() = shakeCov;
  motion::Mat46u J_dq_n = motion::Mat46u::Zero();
  J_dq_n.block<3, 3>(1, 3) = 0.5 * Mat3::Identity();
  return cameraJitterFactor(g, features, N, motion::Mat36u::Zero(), J_dq_n, nClones).rightCols<3>();
}

void predictRobocentric(bayes::TGaussian& g, const std::vector<TFeature>& features,
                        const motion::TMotionIncrement& inc, MatX& scratch, bool lowerInput, int nClones)
{
  if (inc.identity)
  {
    // Stationary: nothing moves on average; the velocities are zero with zero variance.
    g.x.segment<6>(kU).setZero();
    g.P.middleRows<6>(kU).setZero();
    g.P.middleCols<6>(kU).setZero();
    if (inc.noiseCov.isZero())
    {
      if (lowerInput) g.P.triangularView<Eigen::StrictlyUpper>() = g.P.transpose();
      return;
    }
    addCovarianceFactor(g.P, cameraJitterFactor(g, features, inc.noiseCov, inc.J_t_n, inc.J_dq_n, nClones));
    return;
  }
  if (lowerInput) mirrorTransitionInputs(g.P, features, nClones);
  thread_local std::vector<TTransitionBlock> blocks;
  predictRobocentricMean(g, features, inc, blocks, nClones);
  // With a shake, its rank update reads the lower triangle only and mirrors once for both.
  const bool shake = !inc.shakeCov.isZero();
  applyRobocentricTransition(g.P, blocks, scratch, !shake);
  if (shake) addCovarianceFactor(g.P, shakeFactor(g, features, inc.shakeCov, nClones));
}

void mirrorTransitionInputs(MatX& P, const std::vector<TFeature>& features, int nClones)
{
  const Eigen::Index n = P.rows();
  const auto diagonalBlock = [&P](Eigen::Index off, Eigen::Index len) {
    for (Eigen::Index c = off + 1; c < off + len; ++c)
      for (Eigen::Index r = off; r < c; ++r) P(r, c) = P(c, r);
  };
  diagonalBlock(0, 7);
  diagonalBlock(kU, 6);
  P.block<7, 6>(0, kU) = P.block<6, 7>(kU, 0).transpose();
  if (n > kU + 6) P.block(kU, kU + 6, 6, n - kU - 6) = P.block(kU + 6, kU, n - kU - 6, 6).transpose();
  for (int c = 0; c < nClones; ++c) diagonalBlock(poseCloneOffset(c), kPoseCloneDim);
  for (const auto& f : features) diagonalBlock(f.offset, f.dim());
}

void applyPoseCorrection(bayes::TGaussian& g, const std::vector<TFeature>& features, const Vec3& r_CW_new,
                         const Vec4& q_CW_new, double sigmaT, double sigmaTheta, const Vec6& velocity,
                         const Mat6& velocityCov, MatX& scratch, int nClones)
{
  const Vec3 r = g.x.segment<3>(0);
  const Vec4 q = g.x.segment<4>(3);
  motion::TMotionIncrement inc;
  // r' = R(dq)^T (r - t) and q' = conj(dq) (x) q (the prediction's world-pose step) give the new pose.
  inc.dq = math::quatMultiply(q, math::quatConjugate(q_CW_new));
  inc.dq.normalize();
  inc.t = r - math::quatRotate(inc.dq, r_CW_new);
  // Pose error of C' entered through the velocity slots: t + e_t and dq (x) exp(e_theta).
  inc.J_t_u.leftCols<3>().setIdentity();
  Mat4 J_right;
  math::quatMultiply(inc.dq, Vec4(1, 0, 0, 0), nullptr, &J_right);
  inc.J_dq_u.rightCols<3>() = 0.5 * J_right.rightCols<3>();  // d(dq (x) exp(e))/de at e = 0
  inc.noiseCov.topLeftCorner<3, 3>() = Mat3::Identity() * sigmaT * sigmaT;
  inc.noiseCov.bottomRightCorner<3, 3>() = Mat3::Identity() * sigmaTheta * sigmaTheta;
  // uNext = 0, J_uNext_u = 0: the velocities are reset below. Clear them first so that the slots
  // carry only the pose error.
  g.x.segment<6>(kU).setZero();
  g.P.middleRows<6>(kU).setZero();
  g.P.middleCols<6>(kU).setZero();
  predictRobocentric(g, features, inc, scratch, false, nClones);  // (the clones keep their world poses)
  g.x.segment<4>(3).normalize();
  g.x.segment<6>(kU) = velocity;
  g.P.block<6, 6>(kU, kU) = velocityCov;
}

void predictRobocentricMean(bayes::TGaussian& g, const std::vector<TFeature>& features,
                            const motion::TMotionIncrement& inc, std::vector<TTransitionBlock>& blocks, int nClones)
{
  const Vec3& t = inc.t;
  const Vec4& dq = inc.dq;
  blocks.clear();
  blocks.reserve(features.size() + 2 + static_cast<std::size_t>(nClones));

  // A pose T_C_X (the world's, a clone's): r' = R(dq)^T (r - t), q' = conj(dq) (x) q.
  const auto poseBlock = [&](int off) {
    TBlockJac b;
    b.off = off;
    b.len = 7;
    b.D.setZero();
    Mat3 J_p, J_t;
    Mat34 J_dq;
    const Vec3 r2 = features::transformPoint(g.x.segment<3>(off), dq, t, &J_p, &J_t, &J_dq);
    Mat4 J_cq, J_q;
    const Vec4 q2 = math::quatMultiply(math::quatConjugate(dq), g.x.segment<4>(off + 3), &J_cq, &J_q);
    b.D.topLeftCorner<3, 3>() = J_p;
    b.D.bottomRightCorner<4, 4>() = J_q;
    // Chain rule through the increment: d/du = d/dt dt/du + d/d(dq) d(dq)/du.
    b.G.topRows<3>() = J_t * inc.J_t_u + J_dq * inc.J_dq_u;
    b.G.bottomRows<4>() = J_cq * Vec4(1, -1, -1, -1).asDiagonal() * inc.J_dq_u;
    g.x.segment<3>(off) = r2;
    g.x.segment<4>(off + 3) = q2;
    blocks.push_back(b);
  };
  poseBlock(0);
  // Velocities.
  {
    TBlockJac b;
    b.off = kU;
    b.len = 6;
    b.hasG = false;
    b.D.topLeftCorner<6, 6>() = inc.J_uNext_u;
    blocks.push_back(b);
  }
  for (int c = 0; c < nClones; ++c) poseBlock(poseCloneOffset(c));
  // Features.
  for (const auto& f : features)
  {
    TBlockJac b;
    b.off = f.offset;
    b.len = f.dim();
    if (f.kind == EFeatureKind::InverseDepth)
    {
      Mat6 J_y;
      Eigen::Matrix<double, 6, 3> J_t;
      Eigen::Matrix<double, 6, 4> J_dq;
      g.x.segment<6>(f.offset) = features::transformInverseDepth(g.x.segment<6>(f.offset), dq, t, &J_y, &J_t, &J_dq);
      b.D.topLeftCorner<6, 6>() = J_y;
      b.G.topRows<6>() = J_t * inc.J_t_u + J_dq * inc.J_dq_u;
    }
    else
    {
      Mat3 J_p, J_t;
      Mat34 J_dq;
      g.x.segment<3>(f.offset) = features::transformPoint(g.x.segment<3>(f.offset), dq, t, &J_p, &J_t, &J_dq);
      b.D.topLeftCorner<3, 3>() = J_p;
      b.G.topRows<3>() = J_t * inc.J_t_u + J_dq * inc.J_dq_u;
    }
    blocks.push_back(b);
  }
  g.x.segment<6>(kU) = inc.uNext;

  // The impulses act like a perturbation of u: P~ = P + E N E^T.
  g.P.block<6, 6>(kU, kU) += inc.noiseCov;
}

void applyRobocentricTransition(MatX& P, const std::vector<TTransitionBlock>& blocks, MatX& scratch, bool mirror)
{
  const Eigen::Index n = P.rows();
  // P' = A P~ A^T with M = A P~ formed only where P' needs it: on and below the block diagonal
  // (one column block at a time, in a panel) and in the columns of u (first, before P~ is
  // overwritten). Every access runs down columns; fixed-size kernels per pair of block sizes
  // (tiny dynamic products would go through GEMM packing). Then the upper triangle is mirrored.
  scratch.resize(n, 13);  // M(:, u), then the panel of one column block (the widest: the pose, 7)
  const auto Mu = scratch.leftCols<6>();
  {
    const Mat6 Puu = P.block<6, 6>(kU, kU);
    for (const auto& a : blocks)
    {
      auto Ma = scratch.block(a.off, 0, a.len, 6);
      Ma.noalias() = a.D.topLeftCorner(a.len, a.len).lazyProduct(P.block(a.off, kU, a.len, 6));
      if (a.hasG) Ma.noalias() += a.G.topRows(a.len).lazyProduct(Puu);
    }
  }
  const auto panel = scratch.rightCols<7>();
  for (const auto& b : blocks)
  {
    switch (b.len)
    {
      case 3: columnBlock<3>(b, blocks, Mu, P, panel); break;
      case 6: columnBlock<6>(b, blocks, Mu, P, panel); break;
      default: columnBlock<7>(b, blocks, Mu, P, panel); break;
    }
  }
  if (mirror) P.triangularView<Eigen::StrictlyUpper>() = P.transpose();
}

MatX transitionColumns(const MatX& Pt, const std::vector<TTransitionBlock>& blocks, int bi)
{
  const TTransitionBlock& b = blocks[bi];
  const Eigen::Index n = Pt.rows();
  // Y = P~ A_b^T (n x len), then A Y block row by block row.
  MatX Y = Pt.middleCols(b.off, b.len) * b.D.topLeftCorner(b.len, b.len).transpose();
  if (b.hasG) Y.noalias() += Pt.middleCols<6>(kU) * b.G.topRows(b.len).transpose();
  MatX out(n, b.len);
  for (const auto& a : blocks)
  {
    out.middleRows(a.off, a.len).noalias() = a.D.topLeftCorner(a.len, a.len) * Y.middleRows(a.off, a.len);
    if (a.hasG) out.middleRows(a.off, a.len).noalias() += a.G.topRows(a.len) * Y.middleRows<6>(kU);
  }
  return out;
}

MatX transitionBlock(const MatX& Pt, const TTransitionBlock& b)
{
  const auto D = b.D.topLeftCorner(b.len, b.len);
  MatX out = D * Pt.block(b.off, b.off, b.len, b.len) * D.transpose();
  if (b.hasG)
  {
    const auto G = b.G.topRows(b.len);
    const MatX DC = D * Pt.block(b.off, kU, b.len, 6) * G.transpose();
    out += DC + DC.transpose();
    out.noalias() += G * Pt.block<6, 6>(kU, kU) * G.transpose();
  }
  return out;
}

MatX transitionInnovationCovariance(const MatX& Pt, const std::vector<TTransitionBlock>& blocks,
                                    const std::vector<int>& blockAt, const bayes::CSparseJacobian& H)
{
  const Eigen::Index n = Pt.rows();
  const int m = H.rows();
  // Rows of H A: a block J on transition block b gives J D_b on b's columns and J G_b on u.
  struct TRow
  {
    int row, b;
    MatX JD, JG;
  };
  std::vector<TRow> rows;
  rows.reserve(H.blocks().size());
  for (const auto& hb : H.blocks())
  {
    const int bi = hb.col < static_cast<int>(blockAt.size()) ? blockAt[hb.col] : -1;
    if (bi < 0 || blocks[bi].len != hb.J.cols())
      throw std::logic_error("transitionInnovationCovariance: a block of H is not one transition block");
    const TTransitionBlock& b = blocks[bi];
    TRow r{hb.row, bi, hb.J * b.D.topLeftCorner(b.len, b.len), MatX()};
    if (b.hasG) r.JG = hb.J * b.G.topRows(b.len);
    rows.push_back(std::move(r));
  }
  // Y = P~ (H A)^T (n x m), S = (H A) Y.
  MatX Y = MatX::Zero(n, m);
  for (const auto& r : rows)
  {
    const TTransitionBlock& b = blocks[r.b];
    Y.middleCols(r.row, r.JD.rows()).noalias() += Pt.middleCols(b.off, b.len) * r.JD.transpose();
    if (b.hasG) Y.middleCols(r.row, r.JD.rows()).noalias() += Pt.middleCols<6>(kU) * r.JG.transpose();
  }
  MatX S = MatX::Zero(m, m);
  for (const auto& r : rows)
  {
    const TTransitionBlock& b = blocks[r.b];
    S.middleRows(r.row, r.JD.rows()).noalias() += r.JD * Y.middleRows(b.off, b.len);
    if (b.hasG) S.middleRows(r.row, r.JD.rows()).noalias() += r.JG * Y.middleRows<6>(kU);
  }
  return S;
}
}  // namespace immslam::slam

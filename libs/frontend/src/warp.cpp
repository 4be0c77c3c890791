/* imm-monoslam — local affine warp of a planar patch between two views (linearized homography). */
#include <immslam/frontend/frontend.h>
#include <immslam/math/quaternion.h>

#include <cmath>

namespace immslam::frontend
{
Mat2 patchWarp(const camera::CCameraModel& cam, const Vec3& r0, const Vec4& q0, const Vec3& rk,
               const Vec4& qk, const Vec3& p_W, const Vec3& n_W)
{
  const Mat2 I = Mat2::Identity();
  if (!r0.allFinite() || !q0.allFinite() || !rk.allFinite() || !qk.allFinite() ||
      !p_W.allFinite() || !n_W.allFinite())
    return I;
  const Mat3 R_W_C0 = math::quatToRotation(q0);
  const Mat3 R_W_Ck = math::quatToRotation(qk);

  // View 0: the pixel of p_W and the Jacobian of its back-projected unit ray.
  Vec2 u0;
  if (!cam.project(R_W_C0.transpose() * (p_W - r0), u0)) return I;
  Mat32 J_b_u0;
  const Vec3 b_C0 = cam.unproject(u0, &J_b_u0).unitVector();
  const Vec3 d = R_W_C0 * b_C0;  // the ray in W
  const Mat32 J_d_u0 = R_W_C0 * J_b_u0;

  // Plane {x : n.(x - p_W) = 0}; the ray x(u) = r0 + t(u) d(u) meets it at t = n.(p_W - r0) / n.d.
  const double nn = n_W.norm();
  const Vec3 n = nn > 0 ? Vec3(n_W / nn) : d;
  const double nd = n.dot(d);
  if (std::abs(nd) < 1e-6) return I;
  const double t = n.dot(p_W - r0) / nd;
  // Chain rule: dx = dt d + t dd with dt = -(t / n.d) n.dd  =>  dx/du0 = t (I - d n^T / n.d)
  // dd/du0.
  const Mat32 J_x_u0 = t * (Mat3::Identity() - d * n.transpose() / nd) * J_d_u0;

  // View k: the projection Jacobian at p_W.
  Vec2 uk;
  Mat23 J_uk_pC;
  if (!cam.project(R_W_Ck.transpose() * (p_W - rk), uk, &J_uk_pC)) return I;
  const Mat2 A = J_uk_pC * R_W_Ck.transpose() * J_x_u0;
  return A.allFinite() ? A : I;
}
}  // namespace immslam::frontend

/* imm-monoslam — small types shared by the synthetic-sequence renderer (libs/sim). */
#pragma once

#include <immslam/math/types.h>

#include <string>

namespace immslam::sim
{
/** A rigid pose T_A_B (B expressed in A): \f$ p_A = R(q)\,p_B + t \f$, q = [qw qx qy qz]
 * (doc/conventions.md). */
struct TPose
{
  Vec3 t = Vec3::Zero();
  Vec4 q = Vec4(1, 0, 0, 0);
};

/** The true motion of the camera between the previous frame and this one. */
enum class EMotionLabel
{
  Stationary,  ///< neither the centre nor the orientation changed (|v| = |w| = 0)
  Rotation,    ///< the orientation changed, the optical centre did not (|v| = 0)
  General      ///< the optical centre moved
};

/** "stationary", "rotation" or "general" (the words of motion_labels.txt and of the IMM's model
 * families). */
std::string toString(EMotionLabel label);

/** Parses the words of toString(). \throws std::runtime_error naming `context` on another word. */
EMotionLabel motionLabelFromString(const std::string& word, const std::string& context);

/** Pose of one independently moving object at one instant. */
struct TObjectPose
{
  /** The object's id k (its value in the masks, its section [objectK] in the scenario). */
  int id = 0;
  /** T_W_O: the object's frame (centred in the box, axes along its edges) in the world. */
  TPose T_W_O;
};

/** What a ray of the camera hits. */
struct TRayHit
{
  /** 0 for the static world (room and static boxes), k for moving object k. */
  int objectId = 0;
  /** The object hit moves at this time (false for the static world and for an object that still
   * stands before its start_s). */
  bool moving = false;
  /** Textured face hit (index into CWorld::surfaces()). */
  int surfaceId = 0;
  /** The 3-D point hit, in the world frame. */
  Vec3 p_W = Vec3::Zero();
  /** Distance along the ray from the optical centre (the ray direction is a unit vector). */
  double range = 0;
  /** Depth: z of the point in the camera frame. */
  double depth = 0;
};
}  // namespace immslam::sim

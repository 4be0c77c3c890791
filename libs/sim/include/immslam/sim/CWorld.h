/* imm-monoslam — the rendered world: a textured room, static textured boxes and independently
 * moving textured boxes. */
#pragma once

#include <immslam/sim/CTexture.h>
#include <immslam/sim/TScenario.h>
#include <immslam/sim/types.h>

#include <array>
#include <vector>

namespace immslam::sim
{
/** One textured face. */
struct TSurface
{
  CTexture texture;
  /** Brightness factor of the face (a crude shading, so box faces differ). */
  float gain = 1.0f;
  /** Colour tint (B, G, R) used when rendering colour; its luminance is ~1. */
  std::array<float, 3> tint{1.0f, 1.0f, 1.0f};
};

/** An oriented textured box at one instant. Face f = 2 a + (1 if on the + side of axis a), a = 0, 1, 2
 * (x, y, z of the box frame); its texture coordinates are (p[j] + h[j], p[k] + h[k]) with j = (a+1)%3,
 * k = (a+2)%3 and p the point in the box frame. */
struct TBox
{
  /** T_W_B: box frame (centred) in the world. */
  TPose T_W_B;
  /** Half edge lengths. */
  Vec3 half = Vec3::Constant(0.5);
  /** 0: static world, k: moving object k. */
  int objectId = 0;
  /** A moving object that moves at this time (false while it stands still before its start_s). */
  bool moving = false;
  /** Index of face 0 in CWorld::surfaces(); faces follow. */
  int firstSurface = 0;
  /** True for the room: seen from inside. */
  bool inside = false;
};

/** The world of a scenario, built deterministically from its seed: the room (6 faces), `n_boxes`
 * static boxes placed at random (standing on the floor outside the keep-out rectangle, or hung on
 * the walls) and the moving objects (rendered only when `[objects] enabled`). Every face has its
 * own texture from its own random stream, so the static world does not depend on the objects. */
class CWorld
{
 public:
  explicit CWorld(const TScenario& sc);

  /** The room box (inside = true, axis-aligned, static). */
  const TBox& room() const { return m_room; }

  /** The static boxes. */
  const std::vector<TBox>& staticBoxes() const { return m_static; }

  /** The moving objects rendered (empty when the scenario disables them). */
  const std::vector<TMovingObjectSpec>& movingObjects() const { return m_objects; }

  /** T_W_O of a moving object at motion time t (s from the first frame). */
  static TPose objectPose(const TMovingObjectSpec& o, double t);

  /** Every box at motion time t: the room first, then the static boxes, then the moving objects. */
  std::vector<TBox> boxesAt(double t) const;

  /** All textured faces. */
  const std::vector<TSurface>& surfaces() const { return m_surfaces; }

  /** True if the point is at least `clearance` inside the room and outside every static box
   * grown by `clearance`. */
  bool isFree(const Vec3& p_W, double clearance) const;

 private:
  int addSurfaces(const Vec3& half, std::uint64_t seedBase, bool isRoom, double shapesPerUnit2,
                  double texelsPerUnit);

  TBox m_room;
  std::vector<TBox> m_static;
  std::vector<TMovingObjectSpec> m_objects;
  std::vector<int> m_objectFirstSurface;
  std::vector<TSurface> m_surfaces;
};
}  // namespace immslam::sim

/* imm-monoslam — world construction (see CWorld.h). */
#include <immslam/math/quaternion.h>
#include <immslam/sim/CRandom.h>
#include <immslam/sim/CWorld.h>

#include <algorithm>
#include <cmath>

namespace immslam::sim
{
namespace
{
constexpr double kDeg = M_PI / 180.0;

Vec4 yawQuat(double yawRad) { return math::quatFromRotationVector(Vec3(0, yawRad, 0)); }

/** Axis-aligned extent (half sizes) of a box rotated about y. */
Vec3 aabbHalf(const Vec3& half, double yawRad)
{
  const double c = std::abs(std::cos(yawRad)), s = std::abs(std::sin(yawRad));
  return Vec3(c * half.x() + s * half.z(), half.y(), s * half.x() + c * half.z());
}

struct TAabb
{
  Vec3 lo, hi;
  bool overlaps(const TAabb& o, double margin) const
  {
    return (lo.array() - margin < o.hi.array()).all() && (o.lo.array() - margin < hi.array()).all();
  }
};

/** A box hung on a wall of the room sc.room_min..room_max: thin along the wall's normal. */
TBox wallBox(const TScenario& sc, CRandom& rng)
{
  const Vec3& lo = sc.room_min;
  const Vec3& hi = sc.room_max;
  const double floorY = hi.y();
  const double roomH = hi.y() - lo.y();
  TBox b;
  const double lx = hi.x() - lo.x(), lz = hi.z() - lo.z();
  const double pick = rng.uniform(0.0, 2 * (lx + lz));
  const int wall = pick < lx ? 0 : pick < 2 * lx ? 1 : pick < 2 * lx + lz ? 2 : 3;  // z-, z+, x-, x+
  const double depth = rng.uniform(0.08, 0.35);
  const double width = rng.uniform(sc.box_size_min.x(), sc.box_size_max.x());
  const double height = std::min(rng.uniform(sc.box_size_min.y(), sc.box_size_max.y()), 0.6 * roomH);
  const double y = rng.uniform(lo.y() + 0.25 + height / 2, floorY - 0.35 - height / 2);
  if (wall < 2)
  {
    const double x = rng.uniform(lo.x() + width / 2 + 0.1, hi.x() - width / 2 - 0.1);
    const double z = wall == 0 ? lo.z() + depth / 2 : hi.z() - depth / 2;
    b.T_W_B.t = Vec3(x, y, z);
    b.half = 0.5 * Vec3(width, height, depth);
  }
  else
  {
    const double z = rng.uniform(lo.z() + width / 2 + 0.1, hi.z() - width / 2 - 0.1);
    const double x = wall == 2 ? lo.x() + depth / 2 : hi.x() - depth / 2;
    b.T_W_B.t = Vec3(x, y, z);
    b.half = 0.5 * Vec3(depth, height, width);
  }
  return b;
}

/** A box standing on the floor of the room, turned by `yaw` about the vertical; false when it
 * enters the keep-out floor rectangle sc.keep_out. */
bool floorBox(const TScenario& sc, CRandom& rng, TBox& b, double& yaw)
{
  const Vec3& lo = sc.room_min;
  const Vec3& hi = sc.room_max;
  const double floorY = hi.y();
  const double roomH = hi.y() - lo.y();
  Vec3 size;
  for (int a = 0; a < 3; ++a) size[a] = rng.uniform(sc.box_size_min[a], sc.box_size_max[a]);
  size.y() = std::min(size.y(), 0.8 * roomH);
  yaw = rng.uniform(-35.0, 35.0) * kDeg;
  b.half = 0.5 * size;
  const Vec3 ah = aabbHalf(b.half, yaw);
  const double x = rng.uniform(lo.x() + ah.x(), hi.x() - ah.x());
  const double z = rng.uniform(lo.z() + ah.z(), hi.z() - ah.z());
  b.T_W_B.t = Vec3(x, floorY - b.half.y(), z);
  // Outside the keep-out floor rectangle.
  const auto& ko = sc.keep_out;
  return !(x + ah.x() > ko[0] && x - ah.x() < ko[2] && z + ah.z() > ko[1] && z - ah.z() < ko[3]);
}
}  // namespace

int CWorld::addSurfaces(const Vec3& half, std::uint64_t seedBase, bool isRoom, double shapesPerUnit2, double texelsPerUnit)
{
  const int first = static_cast<int>(m_surfaces.size());
  for (int f = 0; f < 6; ++f)
  {
    const int a = f / 2, j = (a + 1) % 3, k = (a + 2) % 3;
    const std::uint64_t seed = CRandom::mix(seedBase + static_cast<std::uint64_t>(f));
    CRandom rng(CRandom::mix(seed ^ 0xA5A5A5A5ULL));
    TSurface s;
    s.texture = CTexture::generate(2 * half[j], 2 * half[k], texelsPerUnit, shapesPerUnit2, seed);
    s.gain = static_cast<float>(isRoom ? rng.uniform(0.85, 1.05) : rng.uniform(0.65, 1.15));
    // A random tint normalized to unit luminance (0.114 B + 0.587 G + 0.299 R).
    std::array<float, 3> t{};
    for (auto& c : t) c = static_cast<float>(rng.uniform(0.55, 1.0));
    const float lum = 0.114f * t[0] + 0.587f * t[1] + 0.299f * t[2];
    for (auto& c : t) c /= lum;
    s.tint = t;
    m_surfaces.push_back(std::move(s));
  }
  return first;
}

CWorld::CWorld(const TScenario& sc)
{
  // The room.
  m_room.T_W_B.t = 0.5 * (sc.room_min + sc.room_max);
  m_room.half = 0.5 * (sc.room_max - sc.room_min);
  m_room.inside = true;
  m_room.firstSurface = addSurfaces(m_room.half, CRandom::streamSeed(sc.seed, "room"), true, sc.shapes_per_unit2,
                                    sc.texels_per_unit);

  // Static boxes: rejection sampling from the layout stream.
  CRandom rng(CRandom::streamSeed(sc.seed, "layout"));
  std::vector<TAabb> placed;
  for (int i = 0; i < sc.n_boxes; ++i)
  {
    for (int attempt = 0; attempt < 200; ++attempt)
    {
      TBox b;
      double yaw = 0;
      if (rng.uniform() < sc.wall_box_fraction)
        b = wallBox(sc, rng);  // hung on a wall: thin along the wall's normal
      else if (!floorBox(sc, rng, b, yaw))  // standing on the floor, turned about the vertical
        continue;
      b.T_W_B.q = yawQuat(yaw);
      const Vec3 ah = aabbHalf(b.half, yaw);
      const TAabb box{b.T_W_B.t - ah, b.T_W_B.t + ah};
      if (std::any_of(placed.begin(), placed.end(), [&](const TAabb& o) { return o.overlaps(box, 0.05); }))
        continue;
      placed.push_back(box);
      m_static.push_back(b);
      break;
    }
  }
  for (std::size_t i = 0; i < m_static.size(); ++i)
    m_static[i].firstSurface = addSurfaces(m_static[i].half, CRandom::streamSeed(sc.seed, "box", i), false,
                                               sc.shapes_per_unit2, sc.texels_per_unit);

  // Moving objects (own texture streams, after every static surface).
  if (sc.objects_enabled)
    for (const auto& o : sc.objects)
    {
      m_objects.push_back(o);
      m_objectFirstSurface.push_back(
          addSurfaces(0.5 * o.size, CRandom::streamSeed(sc.seed, "object", static_cast<std::uint64_t>(o.id)), false,
                      sc.object_shapes_per_unit2, sc.object_texels_per_unit));
    }
}

TPose CWorld::objectPose(const TMovingObjectSpec& o, double tNow)
{
  const double t = std::max(tNow, o.start_s);  // standing still before start_s
  TPose p;
  const double ph = 2.0 * M_PI * t / o.period_s + o.phase_deg * kDeg;
  const Vec3 d = o.direction.normalized();
  if (o.path == EObjectPath::Linear)
    p.t = o.center + o.amplitude * std::sin(ph) * d;
  else
  {
    // Orthonormal basis (e1, e2) of the plane normal to d.
    const Vec3 ref = std::abs(d.x()) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 0, 1);
    const Vec3 e1 = (ref - ref.dot(d) * d).normalized();
    const Vec3 e2 = d.cross(e1);
    p.t = o.center + o.amplitude * (std::cos(ph) * e1 + std::sin(ph) * e2);
  }
  p.q = math::quatMultiply(math::quatFromRotationVector(o.spin_deg_s * (kDeg * t)), yawQuat(o.yaw_deg * kDeg));
  return p;
}

std::vector<TBox> CWorld::boxesAt(double t) const
{
  std::vector<TBox> out;
  out.reserve(1 + m_static.size() + m_objects.size());
  out.push_back(m_room);
  out.insert(out.end(), m_static.begin(), m_static.end());
  for (std::size_t i = 0; i < m_objects.size(); ++i)
  {
    TBox b;
    b.T_W_B = objectPose(m_objects[i], t);
    b.half = 0.5 * m_objects[i].size;
    b.objectId = m_objects[i].id;
    b.moving = t >= m_objects[i].start_s;
    b.firstSurface = m_objectFirstSurface[i];
    out.push_back(b);
  }
  return out;
}

bool CWorld::isFree(const Vec3& p_W, double clearance) const
{
  const Vec3 d = p_W - m_room.T_W_B.t;
  if (((d.cwiseAbs() - m_room.half).array() > -clearance).any()) return false;
  for (const auto& b : m_static)
  {
    const Vec3 pb = math::quatRotate(math::quatConjugate(b.T_W_B.q), p_W - b.T_W_B.t);
    if ((pb.cwiseAbs() - b.half).maxCoeff() < clearance) return false;
  }
  return true;
}
}  // namespace immslam::sim

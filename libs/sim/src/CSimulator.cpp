/* imm-monoslam — scenario rendering and dataset output (see CSimulator.h). */
#include <immslam/io/CDatasetWriter.h>
#include <immslam/math/quaternion.h>
#include <immslam/sim/CRandom.h>
#include <immslam/sim/CSimulator.h>

#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace immslam::sim
{
namespace
{
core::TStampedPose stamped(const TPose& p, double t)
{
  core::TStampedPose s;
  s.timestamp = t;
  s.p_W_C = p.t;
  s.q_W_C = p.q;
  return s;
}

std::string fmtTime(double t)
{
  char b[64];
  std::snprintf(b, sizeof(b), "%.6f", t);
  return b;
}

std::string fmtNum(double x)
{
  char b[64];
  std::snprintf(b, sizeof(b), "%.9g", x);
  return b;
}

std::ofstream openText(const std::filesystem::path& p)
{
  std::ofstream f(p);
  if (!f) throw std::runtime_error("cannot write '" + p.string() + "'");
  return f;
}
/** A point of CSimulator::writePointTracks(): on the static world (object 0, world frame) or on a
 * moving object (its frame). */
struct TTrackPoint
{
  int object = 0;
  Vec3 p = Vec3::Zero();
};

/** The pose T_W_O of moving object `object` at frame k; false when it is not in the scene then. */
bool objectPoseAt(const CSimulator& sim, std::size_t k, int object, TPose& T)
{
  for (const auto& o : sim.objectPoses(k))
    if (o.id == object)
    {
      T = o.T_W_O;
      return true;
    }
  return false;
}

/** The points of CSimulator::writePointTracks(): where random rays of random frames (of the first
 * n) hit, opts.staticPoints on the static world and opts.pointsPerObject on each moving object;
 * `have` counts them by object id (0: static world). */
std::vector<TTrackPoint> sampleTrackPoints(const CSimulator& sim, std::size_t n, const TPointTrackOptions& opts,
                                           const std::vector<TMovingObjectSpec>& objects, CRandom& rng,
                                           std::map<int, int>& have)
{
  const auto& cam = *sim.scenario().camera;
  std::vector<TTrackPoint> points;
  std::map<int, int> wanted{{0, opts.staticPoints}};
  have = {{0, 0}};
  for (const auto& o : objects) wanted[o.id] = opts.pointsPerObject, have[o.id] = 0;
  const int total = opts.staticPoints + opts.pointsPerObject * static_cast<int>(objects.size());
  for (int attempt = 0; attempt < 200 * std::max(total, 1) && static_cast<int>(points.size()) < total; ++attempt)
  {
    const auto k = static_cast<std::size_t>(rng.uniformInt(0, static_cast<int>(n) - 1));
    const Vec2 uv(rng.uniform(0, cam.width()), rng.uniform(0, cam.height()));
    const auto hit = sim.raycast(k, uv);
    if (!hit || !wanted.count(hit->objectId)) continue;
    const int j = hit->objectId;
    if (have[j] >= wanted[j]) continue;
    TTrackPoint p;
    p.object = j;
    p.p = hit->p_W;
    TPose T;
    if (j > 0)
    {
      if (!objectPoseAt(sim, k, j, T)) continue;
      p.p = math::quatRotate(math::quatConjugate(T.q), hit->p_W - T.t);
    }
    points.push_back(p);
    ++have[j];
  }
  return points;
}
}  // namespace

CSimulator::CSimulator(TScenario scenario)
    : m_sc((scenario.validate(), std::move(scenario))),
      m_world(m_sc),
      m_traj(m_sc),
      m_renderer(m_sc.camera, m_sc.threads)
{
  checkClearance();
}

void CSimulator::checkClearance() const
{
  const double c = m_sc.min_clearance;
  for (std::size_t k = 0; k < frameCount(); ++k)
  {
    const Vec3& r = m_traj.pose(k).t;
    if (!m_world.isFree(r, c))
      throw std::runtime_error(m_sc.origin + ": the camera comes closer than min_clearance = " + fmtNum(c) +
                               " to a wall or static box at t = " + fmtTime(motionTime(k)) +
                               " s (position " + fmtNum(r.x()) + " " + fmtNum(r.y()) + " " + fmtNum(r.z()) +
                               "); reduce [motion] amplitude_units, change [world] keep_out or the seed");
    for (const auto& o : m_world.movingObjects())
    {
      const TPose p = CWorld::objectPose(o, motionTime(k));
      const double d = (p.t - r).norm() - 0.5 * o.size.norm();
      if (d < c)
        throw std::runtime_error(m_sc.origin + ": [object" + std::to_string(o.id) + "] comes closer than min_clearance = " +
                                 fmtNum(c) + " to the camera at t = " + fmtTime(motionTime(k)) + " s");
    }
  }
}

core::TStampedPose CSimulator::cameraPose(std::size_t k) const { return stamped(m_traj.pose(k), timestamp(k)); }

core::TTrajectory CSimulator::groundTruth(std::size_t n) const
{
  if (n == 0 || n > frameCount()) n = frameCount();
  core::TTrajectory t;
  t.reserve(n);
  for (std::size_t k = 0; k < n; ++k) t.push_back(cameraPose(k));
  return t;
}

std::vector<TObjectPose> CSimulator::objectPoses(std::size_t k) const
{
  std::vector<TObjectPose> out;
  for (const auto& o : m_world.movingObjects()) out.push_back({o.id, CWorld::objectPose(o, motionTime(k))});
  return out;
}

TSyntheticFrame CSimulator::render(std::size_t k) const
{
  if (k >= frameCount()) throw std::runtime_error("CSimulator::render: frame " + std::to_string(k) + " beyond the script");
  TRenderOptions opts;
  opts.noise_sigma_grey = m_sc.noise_sigma_grey;
  opts.blur_sigma_px = m_sc.blur_sigma_px;
  opts.colour = m_sc.colour;
  opts.noise_seed = CRandom::streamSeed(m_sc.seed, "noise", k);
  auto img = m_renderer.render(m_world, m_world.boxesAt(motionTime(k)), m_traj.pose(k), opts);
  TSyntheticFrame f;
  f.index = k;
  f.timestamp = timestamp(k);
  f.grey = img.grey;
  f.colour = img.colour;
  f.mask = img.mask;
  f.T_W_C = cameraPose(k);
  f.label = motionLabel(k);
  f.objects = objectPoses(k);
  return f;
}

cv::Mat CSimulator::renderMask(std::size_t k) const
{
  TRenderOptions opts;
  opts.mask_only = true;
  return m_renderer.render(m_world, m_world.boxesAt(motionTime(k)), m_traj.pose(k), opts).mask;
}

cv::Mat CSimulator::renderDepth(std::size_t k) const
{
  TRenderOptions opts;
  opts.mask_only = true;
  opts.depth = true;
  return m_renderer.render(m_world, m_world.boxesAt(motionTime(k)), m_traj.pose(k), opts).depth;
}

std::optional<TRayHit> CSimulator::raycast(std::size_t k, const Vec2& uv) const
{
  return m_renderer.raycast(m_world.boxesAt(motionTime(k)), m_traj.pose(k), uv);
}

std::optional<TRayHit> CSimulator::raycast(const core::TStampedPose& T_W_C, const Vec2& uv, double ts) const
{
  TPose p;
  p.t = T_W_C.p_W_C;
  p.q = T_W_C.q_W_C.normalized();
  return m_renderer.raycast(m_world.boxesAt(ts - m_sc.start_time_s), p, uv);
}

std::size_t CSimulator::writePointTracks(const std::string& path, std::size_t n, const TPointTrackOptions& opts) const
{
  if (n == 0 || n > frameCount()) n = frameCount();
  if (opts.staticPoints < 0 || opts.pointsPerObject < 0 || !(opts.noisePx >= 0) || !std::isfinite(opts.noisePx))
    throw std::runtime_error("point tracks: counts must be >= 0 and the noise a finite number >= 0");
  const auto& cam = *m_sc.camera;
  CRandom rng(m_sc.seed * 0x9E3779B97F4A7C15ULL + 0x70696e7473ULL);  // its own stream of the scenario's seed
  const auto& objects = m_world.movingObjects();
  std::map<int, int> have;  // points by object id (0: static world)
  const std::vector<TTrackPoint> points = sampleTrackPoints(*this, n, opts, objects, rng, have);
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "# point tracks rendered by imm-render from " << m_sc.origin << " (seed " << m_sc.seed << "): "
    << have[0] << " static points, " << points.size() - have[0] << " on " << objects.size()
    << " moving objects; projection noise " << opts.noisePx << " px\n"
    << "# timestamp point_id kind x y z u v   (true world position, noisy projection)\n";
  char line[256];
  std::size_t rows = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    const auto T_W_C = cameraPose(k);
    for (std::size_t i = 0; i < points.size(); ++i)
    {
      const TTrackPoint& pt = points[i];
      Vec3 p_W = pt.p;
      TPose T;
      if (pt.object > 0)
      {
        if (!objectPoseAt(*this, k, pt.object, T)) continue;
        p_W = math::quatRotate(T.q, pt.p) + T.t;
      }
      const Vec3 p_C = math::quatRotate(math::quatConjugate(T_W_C.q_W_C), p_W - T_W_C.p_W_C);
      Vec2 uv;
      if (p_C.z() <= 0 || !cam.project(p_C, uv) || !cam.isInImage(uv)) continue;
      // Occluded unless the ray through its projection hits this point first.
      const auto hit = raycast(k, uv);
      if (!hit || hit->objectId != pt.object || (hit->p_W - p_W).norm() > 1e-6 * std::max(1.0, hit->range)) continue;
      const Vec2 z = uv + opts.noisePx * Vec2(rng.normal(), rng.normal());
      if (!cam.isInImage(z)) continue;
      std::snprintf(line, sizeof(line), "%.6f %zu %s %.6f %.6f %.6f %.4f %.4f\n", timestamp(k), i,
                    pt.object == 0 ? "static" : "moving", p_W.x(), p_W.y(), p_W.z(), z.x(), z.y());
      f << line;
      ++rows;
    }
  }
  if (!f) throw std::runtime_error("error writing " + path);
  return rows;
}

TWriteStats CSimulator::writeDataset(const std::string& folder, std::size_t n,
                                     const std::function<void(std::size_t)>& progress) const
{
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (n == 0 || n > frameCount()) n = frameCount();
  namespace fs = std::filesystem;
  const fs::path dir(folder);
  io::CDatasetWriter writer(folder, *m_sc.camera,
                            "rendered by imm-render from " + m_sc.origin + " (seed " + std::to_string(m_sc.seed) + ")");
  fs::create_directories(dir / "masks");

  auto labels = openText(dir / "motion_labels.txt");
  labels << "# true camera motion since the previous frame (frame 0: stationary): stationary (|v| = |w| = 0), "
            "rotation (|v| = 0), general\n# timestamp label\n";
  auto vel = openText(dir / "camera_velocity.txt");
  vel << "# true camera velocities at the frame time: v_W (units/s, world frame), w_C (rad/s, camera frame)\n"
         "# timestamp vx vy vz wx wy wz\n";
  auto objs = openText(dir / "objects_groundtruth.txt");
  objs << "# poses T_W_O of the moving objects (object frame centred in the box, axes along its edges); "
          "object_id = value in masks/\n# timestamp object_id tx ty tz qx qy qz qw\n";
  {
    auto wb = openText(dir / "world_boxes.txt");
    wb << "# boxes of the world: object_id (0 static; the room first, seen from inside; moving objects at t = 0), "
          "centre T_W_B (tx ty tz qx qy qz qw), edge lengths (sx sy sz)\n"
          "# object_id tx ty tz qx qy qz qw sx sy sz\n";
    for (const auto& b : m_world.boxesAt(0.0))
    {
      wb << b.objectId;
      for (int i = 0; i < 3; ++i) wb << ' ' << fmtNum(b.T_W_B.t[i]);
      wb << ' ' << fmtNum(b.T_W_B.q[1]) << ' ' << fmtNum(b.T_W_B.q[2]) << ' ' << fmtNum(b.T_W_B.q[3]) << ' '
         << fmtNum(b.T_W_B.q[0]);
      for (int i = 0; i < 3; ++i) wb << ' ' << fmtNum(2 * b.half[i]);
      wb << '\n';
    }
  }
  {
    auto ini = openText(dir / "scenario.ini");
    ini << m_sc.toIni();
  }

  double renderSeconds = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    const auto r0 = Clock::now();
    const TSyntheticFrame f = render(k);
    renderSeconds += std::chrono::duration<double>(Clock::now() - r0).count();
    const std::string rel = writer.addFrame(f.timestamp, f.colour.empty() ? f.grey : f.colour, &f.T_W_C);
    const std::string maskPath = (dir / "masks" / fs::path(rel).filename()).string();
    if (!cv::imwrite(maskPath, f.mask)) throw std::runtime_error("cannot write '" + maskPath + "'");
    const std::string ts = fmtTime(f.timestamp);
    labels << ts << ' ' << toString(f.label) << '\n';
    const Vec3 v = m_traj.linearVelocity(motionTime(k));
    const Vec3 w = m_traj.angularVelocity(motionTime(k));
    vel << ts;
    for (int i = 0; i < 3; ++i) vel << ' ' << fmtNum(v[i]);
    for (int i = 0; i < 3; ++i) vel << ' ' << fmtNum(w[i]);
    vel << '\n';
    for (const auto& o : f.objects)
      objs << ts << ' ' << o.id << ' ' << fmtNum(o.T_W_O.t.x()) << ' ' << fmtNum(o.T_W_O.t.y()) << ' '
           << fmtNum(o.T_W_O.t.z()) << ' ' << fmtNum(o.T_W_O.q[1]) << ' ' << fmtNum(o.T_W_O.q[2]) << ' '
           << fmtNum(o.T_W_O.q[3]) << ' ' << fmtNum(o.T_W_O.q[0]) << '\n';
    if (progress) progress(k + 1);
  }
  writer.close();
  for (auto* f : {&labels, &vel, &objs})
  {
    f->flush();
    if (!*f) throw std::runtime_error("error writing the text files of '" + folder + "'");
  }
  TWriteStats s;
  s.frames = n;
  s.renderSeconds = renderSeconds;
  s.totalSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return s;
}
}  // namespace immslam::sim

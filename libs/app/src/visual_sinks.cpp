/* imm-monoslam — the visual writers of a run: overlays, live windows, scenes (see
 * output_sinks.h). */
#include "output_sinks.h"

#include <immslam/math/chi2.h>
#include <immslam/viz/overlay.h>
#include <immslam/viz/scene_render.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace immslam::app::detail
{
namespace fs = std::filesystem;

namespace
{
/** The overlay of a frame: search ellipses and matches, the shadow filter's classes, the frame's
 * figures and its dominant model. */
cv::Mat drawFrameOverlay(const TFrameResult& res)
{
  const slam::CMonoSlamIMM& slam = res.slam;
  const auto& r = slam.lastReport();
  const auto& shadowReport = res.report.shadow;
  const double gate = math::chi2Quantile(slam.options().search_probability, 2);
  viz::TOverlayContent oc;
  for (const auto& s : r.searches)
  {
    viz::TSearchView v;
    v.h = s.h;
    v.S = s.S;
    v.gateChi2 = gate;
    v.id = s.id;
    using E = slam::TSearchRecord::EStatus;
    v.status = s.status == E::LowInnovationInlier ? viz::ESearchStatus::Inlier
               : s.status == E::RescuedInlier     ? viz::ESearchStatus::Rescued
               : s.status == E::Rejected          ? viz::ESearchStatus::Rejected
                                                  : viz::ESearchStatus::NotFound;
    if (s.found) v.z = s.z;
    oc.searches.push_back(v);
    // SLAM features are the static ones (MonoSLAMBOT Fig. 4: static / dynamic / pending).
    if (shadowReport && s.found) oc.features.push_back(viz::TFeatureView{s.z, viz::EFeatureClass::Static, s.id});
  }
  if (shadowReport)
    for (const auto& v : shadowReport->views)
      oc.features.push_back(viz::TFeatureView{
          v.uv,
          v.cls == shadow::EShadowClass::Dynamic && !v.incoherent ? viz::EFeatureClass::Dynamic : viz::EFeatureClass::Pending,
          v.id});
  char buf[160];
  std::snprintf(buf, sizeof buf, "frame %lld  t %.3f s  map %d  matched %d", static_cast<long long>(r.frame),
                r.timestamp, r.nMap, r.nMatched);
  oc.textLines.push_back(buf);
  const VecX mu = slam.modelProbabilities();
  if (mu.size() > 1)
  {
    int best = 0;
    mu.maxCoeff(&best);
    std::snprintf(buf, sizeof buf, "model %s  mu %.2f", slam.models()[best].name.c_str(), mu[best]);
    oc.textLines.push_back(buf);
  }
  const io::TFrame& f = res.frame;
  return viz::drawOverlay(f.colour.empty() ? f.grey : f.colour, oc);
}

viz::COverlayWriter::TOptions overlayOptions(const std::string& outDir, const TOutputOptions& opts)
{
  viz::COverlayWriter::TOptions o;
  if (opts.overlays) o.folder = (fs::path(outDir) / "overlays").string();
  if (opts.overlay_video) o.videoPath = (fs::path(outDir) / "overlays.avi").string();
  o.everyN = opts.overlay_every_n;
  return o;
}
}  // namespace

void TTrackHistory::add(const system::TSystemFrame& fr)
{
  if (fr.shadow)
    for (const auto& t : fr.shadow->tracks)
      if (t.measured) lines[t.id].push_back(t.p_W);
}

viz::TSceneContent sceneContent(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                                const TTrackHistory& tracks, const std::string& title,
                                const CSmoothingSink* smoothing)
{
  viz::TSceneContent c;
  c.trajectory = trajectory;
  if (smoothing) c.smoothed = smoothing->published();
  c.camera = std::shared_ptr<const camera::CCameraModel>(&slam.camera(), [](const camera::CCameraModel*) {});
  c.currentCamera = core::TStampedPose{0, slam.cameraPosition(), slam.cameraOrientation()};
  c.title = title;
  for (const auto& f : slam.features())
  {
    const auto e = slam.featureWorldEstimate(f);
    viz::TMapPointView p;
    p.id = f.id;
    p.depthKnown = e.depthKnown;
    p.p_W = e.p_W;
    p.cov_W = e.cov_W;
    if (e.inverseDepth) p.inverseDepth = viz::TInverseDepthView{e.anchor_W, e.theta, e.phi, e.rho, e.cov_tpr};
    c.points.push_back(p);
  }
  // Tracks: the positions within the region of the map (twice its size around it); a track point at
  // an unresolved depth would drag the view far away.
  Eigen::AlignedBox3d box;
  for (const auto& p : c.trajectory) box.extend(p.p_W_C);
  for (const auto& p : c.points)
    if (p.depthKnown) box.extend(p.p_W);
  const double size = box.isEmpty() ? 1.0 : std::max(box.diagonal().norm(), 0.2);
  for (const auto& [id, line] : tracks.lines)
  {
    viz::TTrackView tv{id, {}, viz::ETrackClass::Dynamic, std::nullopt};
    for (const Vec3& p : line)
      if (!box.isEmpty() && box.exteriorDistance(p) < size) tv.polyline_W.push_back(p);
    if (tv.polyline_W.size() >= 2) c.tracks.push_back(std::move(tv));
  }
  return c;
}

COverlaySink::COverlaySink(const std::string& outDir, const TOutputOptions& opts)
    : m_writer(overlayOptions(outDir, opts)), m_everyN(static_cast<std::size_t>(opts.overlay_every_n))
{
}

void COverlaySink::onFrame(const TFrameResult& r)
{
  if (r.processed % m_everyN == 0) m_writer.write(static_cast<long>(r.processed), drawFrameOverlay(r));
}

void COverlaySink::onEnd(const slam::CMonoSlamIMM&, TRunSummary&) { m_writer.close(); }

CLiveViewSink::CLiveViewSink(const TOutputOptions& opts, const core::TTrajectory& trajectory,
                             const CSmoothingSink* smoothing)
    : m_sceneEveryN(static_cast<std::size_t>(std::max(1, opts.gui_scene_every_n))),
      m_trajectory(trajectory),
      m_smoothing(smoothing)
{
}

void CLiveViewSink::onFrame(const TFrameResult& r)
{
  m_tracks.add(r.report);
  if (!m_view.isOpen()) return;
  m_view.showImage(drawFrameOverlay(r));
  if (r.processed % m_sceneEveryN == 0)
    m_view.showScene(sceneContent(r.slam, m_trajectory, m_tracks, "imm-monoslam (live)", m_smoothing));
}

CSceneSink::CSceneSink(const TRunContext& ctx, const TRunInputs& in, const core::TTrajectory& trajectory,
                       const CSmoothingSink* smoothing)
    : m_ctx(ctx), m_in(in), m_trajectory(trajectory), m_smoothing(smoothing)
{
}

void CSceneSink::onFrame(const TFrameResult& r)
{
  m_tracks.add(r.report);
  const int n = m_in.out.scene_every_n;
  if (n <= 0 || r.processed % static_cast<std::size_t>(n) != 0) return;
  char name[64];
  std::snprintf(name, sizeof name, "scene_%06zu", r.processed);
  const auto content = sceneContent(r.slam, m_trajectory, m_tracks, name, m_smoothing);
  const auto scene = viz::buildScene(content, viz::sceneOptionsFitting(content));
  const fs::path dir(m_ctx.args.outDir);
  viz::saveSceneFile(*scene, (dir / (std::string(name) + ".3Dscene")).string());
  viz::renderScenePng(*scene, (dir / (std::string(name) + ".png")).string(), 800, 600);
}

void CSceneSink::onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary)
{
  if (!m_in.out.scene) return;
  auto content = sceneContent(slam, m_trajectory, m_tracks, "imm-monoslam", m_smoothing);
  const auto groundTruth = m_in.source->groundTruth();
  // Ground truth shown in the estimate's frame: the inverse of the Sim(3) that aligned est -> gt.
  if (groundTruth && summary.ate) content.groundTruth = eval::applySim3(summary.ate->sim3().inverse(), *groundTruth);
  const auto scene = viz::buildScene(content, viz::sceneOptionsFitting(content));
  const fs::path dir(m_ctx.args.outDir);
  viz::saveSceneFile(*scene, (dir / "scene.3Dscene").string());
  std::string why;
  if (!viz::renderScenePng(*scene, (dir / "scene.png").string(), 1024, 768, viz::TRenderOptions(), &why))
    m_ctx.log.logStr(mrpt::system::LVL_WARN, "scene.png not rendered: " + why);
}

}  // namespace immslam::app::detail

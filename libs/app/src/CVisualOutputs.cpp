/* imm-monoslam — overlays, scenes and plots of a run. */
#include <immslam/app/CVisualOutputs.h>
#include <immslam/math/chi2.h>
#include <immslam/viz/overlay.h>
#include <immslam/viz/plots.h>
#include <immslam/viz/scene_render.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>

namespace immslam::app
{
namespace fs = std::filesystem;

CVisualOutputs::CVisualOutputs(const std::string& outDir, const TOutputOptions& opts, const slam::CMonoSlamIMM& slam,
                               bool liveWindows)
    : m_dir(outDir), m_opts(opts)
{
  if (liveWindows) m_live = std::make_unique<CLiveView>();
  for (const auto& m : slam.models()) m_modelNames.push_back(m.name);
  if (m_opts.overlays || m_opts.overlay_video)
  {
    viz::COverlayWriter::TOptions o;
    if (m_opts.overlays) o.folder = (fs::path(outDir) / "overlays").string();
    if (m_opts.overlay_video) o.videoPath = (fs::path(outDir) / "overlays.avi").string();
    o.everyN = m_opts.overlay_every_n;
    m_overlays = std::make_unique<viz::COverlayWriter>(o);
  }
}

CVisualOutputs::~CVisualOutputs() = default;

viz::TSceneContent CVisualOutputs::sceneContent(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                                                const std::string& title) const
{
  viz::TSceneContent c;
  c.trajectory = trajectory;
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
  for (const auto& [id, line] : m_tracks)
  {
    viz::TTrackView tv{id, {}, viz::ETrackClass::Dynamic, std::nullopt};
    for (const Vec3& p : line)
      if (!box.isEmpty() && box.exteriorDistance(p) < size) tv.polyline_W.push_back(p);
    if (tv.polyline_W.size() >= 2) c.tracks.push_back(std::move(tv));
  }
  return c;
}

void CVisualOutputs::onFrame(std::size_t frameIndex, const cv::Mat& image, const system::TSystemFrame& fr,
                             const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                             const std::vector<std::string>& extraText)
{
  const auto& r = slam.lastReport();
  if (fr.shadow)
    for (const auto& t : fr.shadow->tracks)
      if (t.measured) m_tracks[t.id].push_back(t.p_W);
  if (m_opts.plots)
  {
    m_times.push_back(r.timestamp);
    m_areas.push_back(r.meanSearchAreaPx2);
    const VecX mu = slam.modelProbabilities();
    m_probs.insert(m_probs.end(), mu.data(), mu.data() + mu.size());
  }
  const double gate = math::chi2Quantile(slam.options().search_probability, 2);
  const bool liveOn = m_live && m_live->isOpen();
  if (liveOn || (m_overlays && frameIndex % static_cast<std::size_t>(m_opts.overlay_every_n) == 0))
  {
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
      if (fr.shadow && s.found) oc.features.push_back(viz::TFeatureView{s.z, viz::EFeatureClass::Static, s.id});
    }
    if (fr.shadow)
      for (const auto& v : fr.shadow->views)
        oc.features.push_back(viz::TFeatureView{
            v.uv, v.cls == shadow::EShadowClass::Dynamic ? viz::EFeatureClass::Dynamic : viz::EFeatureClass::Pending,
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
      std::snprintf(buf, sizeof buf, "model %s  mu %.2f", m_modelNames[best].c_str(), mu[best]);
      oc.textLines.push_back(buf);
    }
    for (const auto& t : extraText) oc.textLines.push_back(t);
    const cv::Mat ov = viz::drawOverlay(image, oc);
    if (m_overlays) m_overlays->write(static_cast<long>(frameIndex), ov);
    if (liveOn)
    {
      m_live->showImage(ov);
      if (frameIndex % static_cast<std::size_t>(std::max(1, m_opts.gui_scene_every_n)) == 0)
        m_live->showScene(sceneContent(slam, trajectory, "imm-monoslam (live)"));
    }
  }
  if (m_opts.scene_every_n > 0 && frameIndex % static_cast<std::size_t>(m_opts.scene_every_n) == 0)
  {
    char name[64];
    std::snprintf(name, sizeof name, "scene_%06zu", frameIndex);
    const auto content = sceneContent(slam, trajectory, name);
    const auto scene = viz::buildScene(content, viz::sceneOptionsFitting(content));
    viz::saveSceneFile(*scene, (fs::path(m_dir) / (std::string(name) + ".3Dscene")).string());
    viz::renderScenePng(*scene, (fs::path(m_dir) / (std::string(name) + ".png")).string(), 800, 600);
  }
}

void CVisualOutputs::finish(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                            const std::optional<core::TTrajectory>& groundTruth,
                            const std::optional<eval::TAteResult>& ate, const std::vector<std::string>& labels,
                            std::vector<std::string>& warnings)
{
  if (m_overlays) m_overlays->close();
  if (m_opts.scene)
  {
    auto content = sceneContent(slam, trajectory, "imm-monoslam");
    if (groundTruth && ate)
    {
      // Ground truth shown in the estimate's frame: the inverse of the Sim(3) that aligned est -> gt.
      content.groundTruth = eval::applySim3(ate->sim3().inverse(), *groundTruth);
    }
    const auto scene = viz::buildScene(content, viz::sceneOptionsFitting(content));
    viz::saveSceneFile(*scene, (fs::path(m_dir) / "scene.3Dscene").string());
    std::string why;
    if (!viz::renderScenePng(*scene, (fs::path(m_dir) / "scene.png").string(), 1024, 768, viz::TRenderOptions(), &why))
      warnings.push_back("scene.png not rendered: " + why);
  }
  if (!m_opts.plots || m_times.empty()) return;
  try
  {
    const auto r = static_cast<Eigen::Index>(m_modelNames.size());
    const MatX P = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        m_probs.data(), static_cast<Eigen::Index>(m_times.size()), r);
    viz::TModelProbabilityPlotOptions po;
    if (labels.size() == m_times.size()) po.truthLabels = labels;
    viz::plotModelProbabilities(m_times, m_modelNames, P, (fs::path(m_dir) / "model_probabilities.png").string(), po);
    po.style = viz::EProbabilityStyle::Lines;
    po.logY = true;
    viz::plotModelProbabilities(m_times, m_modelNames, P, (fs::path(m_dir) / "model_probabilities_log.png").string(),
                                po);
    viz::TSeriesPlotOptions so;
    so.title = "Mean search-ellipse area (95 %)";
    so.yLabel = "area [px^2]";
    so.logY = true;
    viz::TPlotSeries area{m_modelNames.size() > 1 ? "IMM (" + std::to_string(m_modelNames.size()) + " models)"
                                                  : m_modelNames[0],
                          {}, {}};
    for (std::size_t k = 0; k < m_times.size(); ++k)
      if (m_areas[k] > 0)
      {
        area.x.push_back(m_times[k]);
        area.y.push_back(m_areas[k]);
      }
    if (!area.x.empty()) viz::plotSeries({area}, (fs::path(m_dir) / "search_area.png").string(), so);
    if (groundTruth && ate)
    {
      viz::TSeriesPlotOptions ao;
      ao.title = "Absolute trajectory error after Sim(3) alignment";
      ao.yLabel = "position error [ground-truth units]";
      viz::TPlotSeries e{"ATE", {}, {}};
      for (const auto& pe : ate->errors)
      {
        e.x.push_back(pe.tEst);
        e.y.push_back(pe.position);
      }
      viz::plotSeries({e}, (fs::path(m_dir) / "ate.png").string(), ao);
    }
  }
  catch (const std::exception& ex)
  {
    warnings.push_back(std::string("plots not written: ") + ex.what());
  }
}
}  // namespace immslam::app

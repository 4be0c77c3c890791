/* imm-monoslam — per-frame output files of a run. */
#include <immslam/app/COutputFiles.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace immslam::app
{
namespace fs = std::filesystem;

COutputFiles::COutputFiles(const std::string& dir, const slam::CMonoSlamIMM& slam, bool shadow, bool searchLog,
                           bool relativePoses)
    : m_dir(dir)
{
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw std::runtime_error("cannot create output folder '" + dir + "': " + ec.message());
  m_trajFile.open(path("trajectory.txt"));
  if (!m_trajFile) throw std::runtime_error("cannot write '" + path("trajectory.txt") + "'");
  std::vector<std::string> cols{"timestamp"};
  for (const auto& m : slam.models()) cols.push_back(m.name);
  m_probs = std::make_unique<io::CCsvWriter>(path("model_probabilities.csv"), cols);
  m_stats = std::make_unique<io::CCsvWriter>(
      path("frame_stats.csv"),
      std::vector<std::string>{"timestamp", "n_map", "n_predicted", "n_matched", "n_rejected", "mean_search_area_px2",
                               "n_depth_known", "time_ms", "frame", "dt_frames", "n_found", "n_low_innovation",
                               "n_rescued", "n_hypotheses", "n_added", "n_deleted", "n_converted", "slam_ms",
                               "predict_ms", "search_ms", "ransac_ms", "update_ms", "map_ms", "dominant_model",
                               "expanded_search", "sigma_pixel", "shadow_ms", "n_promoted", "n_handed_over",
                               "n_new_shadow", "n_shadow_pending", "n_dynamic", "n_released", "n_dormant_modes", "n_lazy_modes", "lost_frames",
                               "relocalised", "reloc_matches", "reloc_inliers", "reloc_ms", "n_new_first_map",
                               "motion_noise_px", "shake_px"});
  if (shadow)
  {
    m_classes = std::make_unique<io::CCsvWriter>(path("classifications.csv"),
                                                 std::vector<std::string>{"timestamp", "feature_id", "class", "u", "v"});
    m_tracks = std::make_unique<io::CCsvWriter>(
        path("tracks.csv"), std::vector<std::string>{"timestamp", "feature_id", "x", "y", "z", "u", "v", "vx", "vy", "vz", "range",
                                                 "range_rel_sigma"});
  }
  if (searchLog && shadow)
    m_shadowLog = std::make_unique<io::CCsvWriter>(
        path("shadow_log.csv"),
        std::vector<std::string>{"timestamp", "feature_id", "class", "u", "v", "searched", "measured", "age_frames", "score"});
  if (searchLog)
    m_searches = std::make_unique<io::CCsvWriter>(
        path("searches.csv"), std::vector<std::string>{"timestamp", "feature_id", "h_u", "h_v", "s_uu", "s_uv", "s_vv",
                                                       "found", "z_u", "z_v", "score", "status"});
  if (relativePoses)
  {
    // The motion T_{C_j C_k} since the frame at from_timestamp and the upper triangle of its covariance.
    std::vector<std::string> relCols{"timestamp", "from_timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) relCols.push_back("c" + std::to_string(i) + std::to_string(j));
    m_relative = std::make_unique<io::CCsvWriter>(path("relative_poses.csv"), relCols);
  }
}

std::string COutputFiles::path(const std::string& name) const { return (fs::path(m_dir) / name).string(); }

void COutputFiles::addFrame(const system::TSystemFrame& fr, const slam::CMonoSlamIMM& slam)
{
  const auto& r = *fr.slam;
  core::TStampedPose pose{r.timestamp, slam.cameraPosition(), slam.cameraOrientation()};
  m_traj.push_back(pose);
  m_trajFile << core::formatTumLine(pose) << '\n';
  m_trajFile.flush();

  const VecX mu = slam.modelProbabilities();
  std::vector<io::CCsvCell> row{r.timestamp};
  for (int i = 0; i < mu.size(); ++i) row.emplace_back(mu[i]);
  m_probs->addCells(row);
  m_probs->flush();

  int best = 0;
  mu.maxCoeff(&best);
  int nPending = 0, nDynamic = 0;
  if (fr.shadow)
    for (const auto& v : fr.shadow->views) (v.cls == shadow::EShadowClass::Dynamic && !v.incoherent ? nDynamic : nPending)++;
  m_stats->addCells({r.timestamp, r.nMap, r.nPredicted, r.nMatched, r.nRejected, r.meanSearchAreaPx2, r.nDepthKnown,
                     fr.totalMs, r.frame, r.dtFrames, r.nFound, r.nLowInnovation, r.nRescued, r.nHypotheses, r.nAdded,
                     r.nDeleted, r.nConverted, r.timeMs, r.tPredictMs, r.tSearchMs, r.tRansacMs, r.tUpdateMs, r.tMapMs,
                     slam.models()[best].name, r.expandedSearch ? 1 : 0, r.sigmaPixel, fr.shadowMs, fr.promoted,
                     fr.handedOver, fr.newShadow, nPending, nDynamic, fr.released, r.nDormantModes, r.nLazyModes, r.lostFrames,
                     r.relocalised ? 1 : 0, r.nRelocMatches, r.nRelocInliers, r.tRelocMs, fr.newFirstMap,
                     r.motionNoiseAngularPx, r.shakePx});
  if (fr.shadow && m_classes)
  {
    for (const auto& d : fr.shadow->decisions)
      m_classes->addCells({r.timestamp, d.id, shadow::className(d.cls), d.uv.x(), d.uv.y()});
    m_classes->flush();
    // Tracks decided dynamic in this frame that were mapped first start where the map held them.
    for (const auto& m : fr.mappedPast)
      m_tracks->addCells({m.timestamp, m.id, m.p_W.x(), m.p_W.y(), m.p_W.z(), m.uv.x(), m.uv.y(), 0.0, 0.0, 0.0, m.range,
                          m.rangeRelSigma});
    for (const auto& t : fr.shadow->tracks)
      if (t.measured)
      {
        // range: distance from the camera; range_rel_sigma: its relative 1-sigma (sigma_w / w), small
        // for a located point, large for a bearing of unknown depth.
        m_tracks->addCells({r.timestamp, t.id, t.p_W.x(), t.p_W.y(), t.p_W.z(), t.uv.x(), t.uv.y(), t.v_W.x(), t.v_W.y(),
                            t.v_W.z(), (t.p_W - pose.p_W_C).norm(), t.distanceRelativeStd});
      }
    m_tracks->flush();
    if (m_shadowLog)
    {
      // A feature seen moving without a decision (TFeatureView::incoherent) is "held": the overlays and
      // stats.csv count it as pending, a decided dynamic feature is "dynamic".
      for (const auto& v : fr.shadow->views)
        m_shadowLog->addCells({r.timestamp, v.id, v.incoherent ? std::string("held") : shadow::className(v.cls),
                               v.uv.x(), v.uv.y(), v.searched ? 1 : 0, v.measured ? 1 : 0, v.ageFrames, v.score});
      m_shadowLog->flush();
    }
  }
  m_stats->flush();
  if (m_searches)
  {
    static const char* kStatus[] = {"not_found", "inlier", "rescued", "rejected"};
    for (const auto& s : r.searches)
      m_searches->addCells({r.timestamp, s.id, s.h.x(), s.h.y(), s.S(0, 0), s.S(0, 1), s.S(1, 1), s.found ? 1 : 0,
                            s.z.x(), s.z.y(), s.score, kStatus[static_cast<int>(s.status)]});
    m_searches->flush();
  }
  if (m_relative && r.relFrom >= 0)
  {
    std::vector<io::CCsvCell> cells{r.timestamp, r.relFromTimestamp, r.relT.x(), r.relT.y(), r.relT.z(),
                                    r.relQ[1],   r.relQ[2],          r.relQ[3],  r.relQ[0]};
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j) cells.emplace_back(r.relCov(i, j));
    m_relative->addCells(cells);
    m_relative->flush();
  }
}

void COutputFiles::writeMap(const slam::CMonoSlamIMM& slam) const
{
  io::CCsvWriter map(path("map.csv"), {"feature_id", "x", "y", "z", "depth_known", "kind", "n_predicted", "n_matched"});
  for (const auto& f : slam.features())
  {
    const Vec3 p = slam.featurePosition(f);
    map.addCells({f.id, p.x(), p.y(), p.z(), slam.depthKnown(f) ? 1 : 0,
                  f.kind == slam::EFeatureKind::XYZ ? "xyz" : "inverse_depth", f.nPredicted, f.nMatched});
  }
  map.flush();
}
}  // namespace immslam::app

/* slam-eval: evaluation of imm-monoslam's outputs against ground truth (ATE/RPE, motion
 * segmentation, static/dynamic classification, track errors, NIS); see --help. */
#include <immslam/evalapp/slam_eval_app.h>
#include <immslam/refine/bundle_adjust.h>
#include <immslam/sim/pixel_truth.h>

#include <iostream>
#include <sstream>

int main(int argc, char** argv)
{
  immslam::refine::quietSolverLog();  // `reprojection --refine` solves with Ceres
  namespace evalapp = immslam::evalapp;
  evalapp::TSlamEvalTruthSources truth;
  // Tracks on a rendered sequence: the truth at each tracked pixel is ray cast through the
  // renderer's world (eval does not depend on the renderer, so it is plugged in here).
  truth.renderedTrackTruth = [](const std::string& folder, const std::vector<immslam::core::TTrackSample>& samples,
                                double maxDt, std::string& report) {
    immslam::sim::TPixelTruthStats st;
    auto points = immslam::sim::truthAtPixelsOfRenderedFolder(folder, samples, maxDt, &st);
    std::ostringstream s;
    s << st.samples << " rows: " << st.onMoving << " on a moving object, " << st.onStatic << " on the static world, "
      << st.boundary << " on a silhouette or depth step (left out), " << st.noFrame << " without a frame";
    report = s.str();
    return points;
  };
  return evalapp::runSlamEvalApp(std::vector<std::string>(argv, argv + argc), std::cout, std::cerr, truth);
}

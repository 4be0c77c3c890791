/* imm-monoslam — the slam-eval program: subcommand dispatch and the segmentation, classification
 * and NIS reports (the ATE report is runEvalApp(), eval_app.cpp). */
#include <immslam/eval/ate.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/core/TTrajectory.h>
#include <immslam/evalapp/eval_app.h>
#include <immslam/refine/bundle_adjust.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/eval/relative_nees.h>
#include <immslam/eval/search_nis.h>
#include <immslam/eval/segmentation.h>
#include <immslam/evalapp/slam_eval_app.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <stdexcept>

namespace immslam::evalapp
{
using namespace immslam::eval;
using namespace immslam::refine;
namespace
{
struct TUsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/** A parsed subcommand line: positionals, flags and "--name V" / "--name=V" values. */
struct TParsed
{
  std::vector<std::string> positional;
  std::map<std::string, std::string> values;
  bool help = false;

  std::optional<std::string> value(const std::string& name) const
  {
    const auto it = values.find(name);
    return it == values.end() ? std::nullopt : std::optional<std::string>(it->second);
  }
};

TParsed parse(const std::vector<std::string>& args, std::size_t first, const std::vector<std::string>& valueOptions)
{
  TParsed p;
  for (std::size_t i = first; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      p.help = true;
      continue;
    }
    if (a.size() < 2 || a[0] != '-')
    {
      p.positional.push_back(a);
      continue;
    }
    const std::size_t eq = a.find('=');
    const std::string name = a.substr(0, eq);
    bool known = false;
    for (const auto& o : valueOptions) known = known || o == name;
    if (!known) throw TUsageError("unknown option '" + a + "'");
    if (p.values.count(name)) throw TUsageError(name + " given twice");
    if (eq != std::string::npos)
      p.values[name] = a.substr(eq + 1);
    else if (i + 1 < args.size())
      p.values[name] = args[++i];
    else
      throw TUsageError(name + " needs a value");
  }
  return p;
}

double parseNumber(const std::string& name, const std::string& s, double lo, double hi)
{
  double v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v) || v < lo || v > hi)
    throw TUsageError(name + ": '" + s + "' is not a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

/** The value of option `name` as a number in [lo, hi], or `def` when the option is absent. */
double numberOr(const TParsed& p, const std::string& name, double lo, double hi, double def)
{
  const auto v = p.value(name);
  return v ? parseNumber(name, *v, lo, hi) : def;
}

/** Largest timestamp difference when joining files (`--max-dt`, default 0.1 ms). */
double maxDtOption(const TParsed& p) { return numberOr(p, "--max-dt", 0, 1e9, 1e-4); }

void requirePositional(const TParsed& p, std::size_t n, const std::string& what)
{
  if (p.positional.size() != n)
    throw TUsageError("expected " + what + ", got " + std::to_string(p.positional.size()) + " file(s)");
}

std::string segmentationUsage(const std::string& prog)
{
  return "Usage: " + prog + " model_probabilities.csv motion_labels.txt [--exclude S] [--max-dt S]\n"
         "Motion segmentation of an IMM run: per frame, the model family (name before '_') with the\n"
         "highest summed probability against the true label (stationary|rotation|general) of the\n"
         "renderer's motion_labels.txt. Frames are joined by timestamp.\n"
         "  --exclude S  frames closer than S seconds to a label change are not counted (default 0.5)\n"
         "  --max-dt S   largest timestamp difference when joining the files (default 0.0001)\n";
}

std::string classificationUsage(const std::string& prog)
{
  return "Usage: " + prog + " classifications.csv (--masks DATASET_FOLDER | --points points_groundtruth.txt)\n"
         "       [--radius PX] [--max-dt S]\n"
         "Static/dynamic decisions of the shadow filter against ground truth:\n"
         "  --masks DIR   a rendered dataset folder: rgb.txt names the image of each timestamp and\n"
         "                masks/<name> its object mask (0 static, > 0 moving); a decision is truly\n"
         "                dynamic if a pixel of the (2 PX + 1)^2 neighbourhood is non-zero (PX default 1)\n"
         "  --points F    projected ground-truth points 'timestamp point_id kind x y z u v': the\n"
         "                nearest point within PX pixels (default 3) gives the truth; decisions\n"
         "                farther from every point are reported as unmatched\n"
         "  --radius PX   see above\n"
         "  --max-dt S    largest timestamp difference when joining the files (default 0.0001)\n";
}

std::string tracksUsage(const std::string& prog)
{
  return "Usage: " + prog + " tracks.csv (points_groundtruth.txt | RENDERED_FOLDER) --est trajectory.txt\n"
         "       [--gt groundtruth.txt] [--radius PX] [--max-dt S] [--max-rel-sigma R]\n"
         "Position error of the tracked dynamic features (tracks.csv) against the ground truth, after\n"
         "mapping each estimated position onto the ground truth by the Sim(3) that aligns the estimated\n"
         "camera trajectory (--est) with the true one (--gt), the same alignment as 'ate'.\n"
         "  points_groundtruth.txt  moving ground-truth points 'timestamp point_id kind x y z u v': each\n"
         "                row is joined with the point nearest to its pixel in its frame (within PX\n"
         "                pixels, default 3)\n"
         "  RENDERED_FOLDER  a dataset folder written by imm-render: the truth of a row is the surface\n"
         "                point its measured pixel sees at its timestamp (ray cast through the folder's\n"
         "                scenario.ini); rows on an object's silhouette (no single point) are left\n"
         "                out; --gt defaults to the folder's groundtruth.txt\n"
         "With the column range_rel_sigma (the relative 1-sigma of the distance, which imm-monoslam\n"
         "writes) the error is also given over the located samples only, range_rel_sigma <= R\n"
         "(--max-rel-sigma R, default 0.5): a track starts as a bearing of unknown depth.\n"
         "  --max-dt S    largest timestamp difference when joining the files (default 0.0001)\n";
}

std::string nisUsage(const std::string& prog)
{
  return "Usage: " + prog + " searches.csv [--confidence C]\n"
         "NIS (z-h)^T S^-1 (z-h) of the matches used in the update (status inlier or rescued) of the\n"
         "app's searches.csv ([output] search_log = true): mean, mean per dof (1 for a consistent\n"
         "filter) and the fraction inside the chi-square(2) bound of probability C (default 0.95).\n";
}

std::string relativeNeesUsage(const std::string& prog)
{
  return "Usage: " + prog + " relative_poses.csv GT.txt [--est trajectory.txt] [--confidence C] [--max-dt S]\n"
         "Consistency of the SLAM filter's relative poses: the NEES of every motion of the app's\n"
         "relative_poses.csv ([output] relative_pose_lag = N) against the ground truth GT.txt (TUM,\n"
         "T_world_camera): the rotation's (3 dof) and, with the run's trajectory for the map's scale\n"
         "(its Sim(3) alignment onto GT.txt), the whole pose's (6 dof); mean, median and the fraction\n"
         "inside the chi-square bound of probability C (default 0.95), each against a consistent\n"
         "filter's. --max-dt: largest timestamp difference when joining the files (default 0.0001).\n";
}

int runRelativeNees(const std::string& prog, const std::vector<std::string>& args, std::ostream& out)
{
  const TParsed p = parse(args, 2, {"--est", "--confidence", "--max-dt"});
  if (p.help) return out << relativeNeesUsage(prog), 0;
  requirePositional(p, 2, "relative_poses.csv GT.txt");
  const double conf = numberOr(p, "--confidence", 1e-9, 1 - 1e-9, 0.95);
  const double maxDt = maxDtOption(p);
  const auto rows = readRelativePosesCsv(p.positional[0]);
  const core::TTrajectory gt = core::readTumTrajectory(p.positional[1]);
  double scale = 0;
  if (const auto est = p.value("--est")) scale = computeAte(core::readTumTrajectory(*est), gt, EAlignment::Sim3, maxDt).scale;
  out << "relative poses : " << p.positional[0] << "\n"
      << computeRelativeNees(rows, gt, scale, maxDt, conf).summary();
  return 0;
}

int runSegmentation(const std::string& prog, const std::vector<std::string>& args, std::ostream& out)
{
  const TParsed p = parse(args, 2, {"--exclude", "--max-dt"});
  if (p.help) return out << segmentationUsage(prog), 0;
  requirePositional(p, 2, "model_probabilities.csv motion_labels.txt");
  const double exclude = numberOr(p, "--exclude", 0, 1e9, 0.5);
  const double maxDt = maxDtOption(p);
  const TModelProbabilities probs = readModelProbabilitiesCsv(p.positional[0]);
  const TMotionLabels labels = readMotionLabels(p.positional[1]);
  if (probs.times.empty()) throw std::runtime_error(p.positional[0] + ": no rows");
  if (labels.times.empty()) throw std::runtime_error(p.positional[1] + ": no labels");
  TSegmentationResult r;
  try
  {
    r = segmentationAccuracy(probs, labels, exclude, maxDt);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(p.positional[0] + " vs " + p.positional[1] + ": " + e.what());
  }
  out << "probabilities: " << p.positional[0] << " (" << probs.times.size() << " frames, " << probs.modelNames.size()
      << " models)\nlabels       : " << p.positional[1] << " (" << labels.times.size() << " frames)\n"
      << r.summary();
  return 0;
}

int runClassification(const std::string& prog, const std::vector<std::string>& args, std::ostream& out)
{
  const TParsed p = parse(args, 2, {"--masks", "--points", "--radius", "--max-dt"});
  if (p.help) return out << classificationUsage(prog), 0;
  requirePositional(p, 1, "classifications.csv");
  const auto masks = p.value("--masks"), points = p.value("--points");
  if (masks.has_value() == points.has_value()) throw TUsageError("give exactly one of --masks DIR and --points FILE");
  const double maxDt = maxDtOption(p);
  double radius = masks ? 1 : 3;
  if (const auto rv = p.value("--radius"))
  {
    radius = parseNumber("--radius", *rv, 0, 1e4);
    if (masks && radius != std::floor(radius)) throw TUsageError("--radius: a whole number of pixels with --masks");
  }
  const auto decisions = readClassificationsCsv(p.positional[0]);
  TClassificationResult r;
  if (masks)
    r = classificationAgainstMaskFolder(decisions, *masks, static_cast<int>(radius), maxDt);
  else
    r = classificationAgainstPoints(decisions, readPointsGroundTruth(*points), radius, maxDt);
  out << "decisions    : " << p.positional[0] << " (" << decisions.size() << ")\n"
      << "ground truth : " << (masks ? "masks of " + *masks : "points of " + *points) << " (radius " << radius
      << " px)\n"
      << r.summary();
  return 0;
}

int runTracks(const std::string& prog, const std::vector<std::string>& args, std::ostream& out,
              const TSlamEvalTruthSources& truth)
{
  const TParsed p = parse(args, 2, {"--est", "--gt", "--radius", "--max-dt", "--max-rel-sigma"});
  if (p.help) return out << tracksUsage(prog), 0;
  requirePositional(p, 2, "tracks.csv (points_groundtruth.txt | RENDERED_FOLDER)");
  const std::string& truthPath = p.positional[1];
  const bool rendered = std::filesystem::is_directory(truthPath);
  if (rendered && !truth.renderedTrackTruth)
    throw TUsageError("'" + truthPath + "' is a folder: this build has no renderer to compute its ground truth");
  const auto est = p.value("--est");
  const auto gt = p.value("--gt") ? p.value("--gt")
                  : rendered      ? std::optional<std::string>((std::filesystem::path(truthPath) / "groundtruth.txt").string())
                                  : std::nullopt;
  if (!est || !gt) throw TUsageError("--est trajectory.txt and --gt groundtruth.txt are needed (the alignment)");
  const double maxDt = maxDtOption(p);
  // A rendered folder's truth is computed at each row's own pixel: a sub-pixel radius joins it.
  const double radius = numberOr(p, "--radius", 0, 1e4, rendered ? 0.5 : 3);
  const TAteResult ate = computeAte(core::readTumTrajectory(*est), core::readTumTrajectory(*gt), EAlignment::Sim3, 0.01);
  const auto samples = readTracksCsv(p.positional[0]);
  const double maxRel = numberOr(p, "--max-rel-sigma", 1e-12, 1e12, 0.5);
  std::string truthReport;
  const auto points = rendered ? truth.renderedTrackTruth(truthPath, samples, maxDt, truthReport)
                               : readPointsGroundTruth(truthPath);
  const TTrackErrorResult r = trackErrorAgainstPoints(samples, points, ate.sim3(), radius, maxDt);
  out << "tracks       : " << p.positional[0] << "\n"
      << "ground truth : " << (rendered ? "surface points at the tracked pixels, rendered folder " : "points of ")
      << truthPath << " (radius " << radius << " px)\n";
  if (!truthReport.empty()) out << "               " << truthReport << "\n";
  out << "alignment    : Sim(3) of " << *est << " onto " << *gt << " (" << ate.nPairs << " poses, scale " << ate.scale
      << "; camera ATE " << ate.rmse << ")\n"
      << r.summary();
  const bool hasSigma = std::any_of(samples.begin(), samples.end(), [](const core::TTrackSample& t) { return std::isfinite(t.rangeRelSigma); });
  if (hasSigma)
  {
    const TTrackErrorResult located = trackErrorAgainstPoints(samples, points, ate.sim3(), radius, maxDt, maxRel);
    out << "located samples only (range_rel_sigma <= " << maxRel << "): " << located.matched << " samples of "
        << located.matchedTracks << " tracks";
    if (located.matched > 0)
      out << ", position error RMS " << located.rmse << ", median " << located.median << ", max " << located.max
          << " at a median distance of " << located.medianRange;
    out << "\n";
  }
  return 0;
}

std::string reprojectionUsage(const std::string& prog)
{
  return "Usage: " + prog + " searches.csv POSES.txt --calib calib.txt [--min-views N] [--min-per-pose N]\n"
         "       [--max-dt S] [--refine OUT.txt] [--huber PX] [--iterations N]\n"
         "How well a trajectory (an estimate or a ground truth, TUM format) explains the image\n"
         "measurements the SLAM used (searches.csv rows with status inlier or rescued, written with\n"
         "[output] search_log = true): every feature seen from N poses is triangulated from the\n"
         "given poses and its reprojection error reported (undistorted pixels). A consistent\n"
         "trajectory leaves about the matching noise on every feature; a biased one leaves a few\n"
         "pixels on the features off the structure it was computed from.\n"
         "  --calib F       the camera of the run (calib.txt format), required\n"
         "  --min-views N   features measured from fewer poses are left out (default 8)\n"
         "  --min-per-pose N  poses measuring fewer of those features are left out, with their\n"
         "                  measurements: they do not determine the pose (default 6)\n"
         "  --max-dt S      largest timestamp difference when joining rows to poses (default 0.0001)\n"
         "  --refine OUT    then bundle-adjust poses and points from there (Levenberg-Marquardt,\n"
         "                  Huber cost, first pose held) and write the refined trajectory (the poses\n"
         "                  kept) to OUT: the best rigid explanation of the measurements near the\n"
         "                  given one\n"
         "  --huber PX      Huber threshold of the refinement (default 2)\n"
         "  --iterations N  refinement iterations at most (default 100)\n";
}

int runReprojection(const std::string& prog, const std::vector<std::string>& args, std::ostream& out)
{
  const TParsed p = parse(args, 2, {"--calib", "--min-views", "--min-per-pose", "--max-dt", "--refine", "--huber", "--iterations"});
  if (p.help) return out << reprojectionUsage(prog), 0;
  requirePositional(p, 2, "searches.csv POSES.txt");
  if (!p.value("--calib")) throw TUsageError("--calib is required (the camera of the run)");
  const int minViews = static_cast<int>(numberOr(p, "--min-views", 2, 1e9, 8));
  const int minPerPose = static_cast<int>(numberOr(p, "--min-per-pose", 1, 1e9, 6));
  const double maxDt = maxDtOption(p);
  TBundleOptions bo;
  bo.huberPx = numberOr(p, "--huber", 1e-3, 1e6, bo.huberPx);
  bo.maxIterations = static_cast<int>(numberOr(p, "--iterations", 1, 1e6, bo.maxIterations));
  const auto cam = camera::loadCalibFile(*p.value("--calib"));
  const auto rows = readSearchesCsv(p.positional[0]);
  const core::TTrajectory poses = core::readTumTrajectory(p.positional[1]);
  TBundleProblem prob;
  try
  {
    prob = makeBundleProblem(rows, poses, *cam, maxDt, minViews, minPerPose);
  }
  catch (const std::runtime_error& e)
  {
    throw std::runtime_error(p.positional[0] + " with " + p.positional[1] + ": " + e.what());
  }
  out << "searches        : " << p.positional[0] << "\n"
      << "poses           : " << p.positional[1] << " (" << poses.size() << ")\n"
      << "-- triangulated from the given poses\n"
      << reprojectionStats(prob).summary();
  if (const auto refined = p.value("--refine"))
  {
    const TBundleResult r = bundleAdjust(prob, bo);
    out << "-- after bundle adjustment (" << r.iterations << " iterations" << (r.converged ? ", converged" : "")
        << (r.unused ? ", " + std::to_string(r.unused) + " measurements behind their camera left out" : "")
        << (r.components > 1 ? ", " + std::to_string(r.components) + " unrelated blocks, each in its own frame" : "")
        << "; robust cost per measurement " << r.initialCost << " -> " << r.finalCost << " px^2)\n"
        << reprojectionStats(prob).summary();
    core::writeTumTrajectory(prob.poses, *refined);
    out << "refined poses   : " << *refined << "\n";
  }
  return 0;
}

int runNis(const std::string& prog, const std::vector<std::string>& args, std::ostream& out)
{
  const TParsed p = parse(args, 2, {"--confidence"});
  if (p.help) return out << nisUsage(prog), 0;
  requirePositional(p, 1, "searches.csv");
  const double conf = numberOr(p, "--confidence", 1e-9, 1 - 1e-9, 0.95);
  const auto rows = readSearchesCsv(p.positional[0]);
  out << "searches     : " << p.positional[0] << "\n" << computeSearchNis(rows, conf).summary();
  return 0;
}
}  // namespace

std::string slamEvalAppUsage(const std::string& prog)
{
  return "Usage: " + prog + " COMMAND ARGS... [options]   (" + prog + " COMMAND --help for details)\n"
         "Evaluation of imm-monoslam's outputs against ground truth.\n"
         "  " + prog + " ate EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA [--rpe-csv F]] [--json]\n"
         "      absolute trajectory error after Sim(3) (default) or SE(3) alignment, also relative to\n"
         "      the path length; RPE over DELTA frames. '" + prog + " EST.txt GT.txt ...' is the same.\n"
         "  " + prog + " segmentation model_probabilities.csv motion_labels.txt [--exclude S]\n"
         "      motion segmentation accuracy of the IMM bank (most probable family vs true label)\n"
         "  " + prog + " classification classifications.csv (--masks DATASET_FOLDER | --points\n"
         "      points_groundtruth.txt) [--radius PX]: static/dynamic confusion matrix\n"
         "  " + prog + " tracks tracks.csv (points_groundtruth.txt | RENDERED_FOLDER) --est EST.txt [--gt GT.txt]\n"
         "      position error of the tracked moving points after the camera's Sim(3) alignment\n"
         "  " + prog + " nis searches.csv: NIS of the matches used in the update vs chi-square(2)\n"
         "  " + prog + " relative-nees relative_poses.csv GT.txt [--est trajectory.txt]: NEES of the\n"
         "      filter's relative poses (its consistency) against ground truth\n"
         "  " + prog + " reprojection searches.csv POSES.txt --calib calib.txt [--refine OUT.txt]\n"
         "      reprojection error of the SLAM's measurements given a trajectory; bundle adjustment\n"
         "  " + prog + " --help\n"
         "Exit status: 0 success, 1 bad input (the message names the file and line), 2 bad usage.\n";
}

int runSlamEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                   const TSlamEvalTruthSources& truth)
{
  const std::string prog =
      args.empty() || args[0].empty() ? "slam-eval" : std::filesystem::path(args[0]).filename().string();
  if (args.size() < 2)
  {
    err << prog << ": no command given\n" << slamEvalAppUsage(prog);
    return 2;
  }
  const std::string& cmd = args[1];
  if (cmd == "--help" || cmd == "-h")
  {
    out << slamEvalAppUsage(prog);
    return 0;
  }
  if (cmd == "ate" || (cmd != "segmentation" && cmd != "classification" && cmd != "tracks" && cmd != "nis" &&
                        cmd != "reprojection" && cmd != "relative-nees"))
  {
    // ATE: the subcommand, or the old form (imm-eval) 'slam-eval EST.txt GT.txt ...'.
    std::vector<std::string> a{cmd == "ate" ? prog + " ate" : prog};
    a.insert(a.end(), args.begin() + (cmd == "ate" ? 2 : 1), args.end());
    return runEvalApp(a, out, err);
  }
  const std::string sub = prog + " " + cmd;
  try
  {
    if (cmd == "segmentation") return runSegmentation(sub, args, out);
    if (cmd == "classification") return runClassification(sub, args, out);
    if (cmd == "tracks") return runTracks(sub, args, out, truth);
    if (cmd == "reprojection") return runReprojection(sub, args, out);
    if (cmd == "relative-nees") return runRelativeNees(sub, args, out);
    return runNis(sub, args, out);
  }
  catch (const TUsageError& e)
  {
    err << sub << ": " << e.what() << "\n"
        << (cmd == "segmentation"     ? segmentationUsage(sub)
            : cmd == "classification" ? classificationUsage(sub)
            : cmd == "tracks"         ? tracksUsage(sub)
            : cmd == "reprojection"   ? reprojectionUsage(sub)
            : cmd == "relative-nees"  ? relativeNeesUsage(sub)
                                      : nisUsage(sub));
    return 2;
  }
  catch (const std::exception& e)
  {
    err << sub << ": " << e.what() << "\n";
    return 1;
  }
}
}  // namespace immslam::evalapp

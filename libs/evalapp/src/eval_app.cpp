/* imm-monoslam — the ATE report of slam-eval: ATE (and optionally RPE) of a TUM trajectory. */
#include <immslam/core/TTrajectory.h>
#include <immslam/eval/ate.h>
#include <immslam/evalapp/eval_app.h>
#include <immslam/eval/rpe.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace immslam::evalapp
{
using namespace immslam::eval;
namespace
{
struct TAppOptions
{
  std::string estPath, gtPath;
  EAlignment alignment = EAlignment::Sim3;
  bool alignmentGiven = false;
  double maxDt = 0.01;
  int rpeDelta = 0;  // 0: no RPE
  std::string rpeCsvPath;  // --rpe-csv: one row per relative motion ("" none)
  bool json = false;
  bool help = false;
};

struct TUsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

bool parseNumber(const std::string& s, double& v)
{
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

TAppOptions parseArgs(const std::vector<std::string>& args)
{
  TAppOptions o;
  std::vector<std::string> positional;
  const auto setAlignment = [&](EAlignment a, const std::string& flag) {
    if (o.alignmentGiven && o.alignment != a)
      throw TUsageError("conflicting alignment options (" + flag + ")");
    o.alignment = a;
    o.alignmentGiven = true;
  };
  for (size_t i = 1; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    // Options with a value: "--opt V" or "--opt=V".
    const auto value = [&](const std::string& name) -> std::optional<std::string> {
      if (a == name)
      {
        if (i + 1 >= args.size()) throw TUsageError(name + " needs a value");
        return args[++i];
      }
      if (a.rfind(name + "=", 0) == 0) return a.substr(name.size() + 1);
      return std::nullopt;
    };
    if (a == "--help" || a == "-h")
      o.help = true;
    else if (a == "--sim3")
      setAlignment(EAlignment::Sim3, a);
    else if (a == "--se3")
      setAlignment(EAlignment::SE3, a);
    else if (a == "--no-align")
      setAlignment(EAlignment::None, a);
    else if (a == "--json")
      o.json = true;
    else if (auto v = value("--max-dt"))
    {
      if (!parseNumber(*v, o.maxDt) || !std::isfinite(o.maxDt) || o.maxDt < 0)
        throw TUsageError("--max-dt: '" + *v + "' is not a number of seconds >= 0");
    }
    else if (auto v2 = value("--rpe"))
    {
      double d = 0;
      if (!parseNumber(*v2, d) || d < 1 || d != std::floor(d) || d > 1e9)
        throw TUsageError("--rpe: '" + *v2 + "' is not a frame delta >= 1");
      o.rpeDelta = static_cast<int>(d);
    }
    else if (auto v3 = value("--rpe-csv"))
    {
      if (v3->empty()) throw TUsageError("--rpe-csv needs a file name");
      o.rpeCsvPath = *v3;
    }
    else if (a.size() > 1 && a[0] == '-')
      throw TUsageError("unknown option '" + a + "'");
    else
      positional.push_back(a);
  }
  if (o.help) return o;
  if (!o.rpeCsvPath.empty() && o.rpeDelta == 0) throw TUsageError("--rpe-csv needs --rpe DELTA");
  if (positional.size() != 2)
    throw TUsageError("expected 2 files (EST.txt GT.txt), got " + std::to_string(positional.size()));
  o.estPath = positional[0];
  o.gtPath = positional[1];
  return o;
}

std::string jsonString(const std::string& s)
{
  std::string out = "\"";
  for (const char c : s)
  {
    if (c == '"' || c == '\\')
      out += std::string("\\") + c;
    else if (static_cast<unsigned char>(c) < 0x20)
    {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += buf;
    }
    else
      out += c;
  }
  return out + "\"";
}

std::string jsonNumber(double v)
{
  if (!std::isfinite(v)) return "null";
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << std::setprecision(12) << v;
  return s.str();
}

core::TTrajectory readNonEmpty(const std::string& path)
{
  core::TTrajectory t = core::readTumTrajectory(path);
  if (t.empty()) throw std::runtime_error(path + ": no poses in trajectory file");
  return t;
}

/** --rpe-csv: every compared relative motion, in time order (TRpePairError; NaN written "nan").
 * \throws std::runtime_error naming the file if it cannot be written. */
void writeRpeCsv(const std::string& path, const TRpeResult& rpe)
{
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << std::setprecision(10);
  s << "t_start,t_end,translation_error,rotation_error_deg,direction_error_deg,local_scale\n";
  const auto num = [&](double v) -> std::ostream& { return std::isfinite(v) ? (s << v) : (s << "nan"); };
  for (const auto& e : rpe.errors)
  {
    num(e.tStart) << ',';
    num(e.tEnd) << ',';
    num(e.translation) << ',';
    num(e.rotationDeg) << ',';
    num(e.directionDeg) << ',';
    num(e.scaleRatio) << '\n';
  }
  std::ofstream f(path, std::ios::binary);
  if (f) f << s.str();
  if (!f || !f.flush()) throw std::runtime_error(path + ": cannot write the RPE table");
}

/** The --json report: one JSON object. */
std::string jsonReport(const TAppOptions& o, std::size_t nEst, std::size_t nGt, const TAteResult& ate,
                       const std::optional<TRpeResult>& rpe)
{
  std::ostringstream j;
  j << "{\n";
  j << "  \"est\": " << jsonString(o.estPath) << ",\n";
  j << "  \"gt\": " << jsonString(o.gtPath) << ",\n";
  j << "  \"n_est\": " << nEst << ",\n";
  j << "  \"n_gt\": " << nGt << ",\n";
  j << "  \"alignment\": " << jsonString(alignmentName(o.alignment)) << ",\n";
  j << "  \"max_dt\": " << jsonNumber(o.maxDt) << ",\n";
  j << "  \"n_pairs\": " << ate.nPairs << ",\n";
  j << "  \"ate_rmse\": " << jsonNumber(ate.rmse) << ",\n";
  j << "  \"ate_mean\": " << jsonNumber(ate.mean) << ",\n";
  j << "  \"ate_median\": " << jsonNumber(ate.median) << ",\n";
  j << "  \"ate_max\": " << jsonNumber(ate.max) << ",\n";
  j << "  \"scale\": " << jsonNumber(ate.scale) << ",\n";
  j << "  \"alignment_rank\": " << ate.alignmentRank << ",\n";
  j << "  \"path_length\": " << jsonNumber(ate.pathLength) << ",\n";
  j << "  \"extent\": " << jsonNumber(ate.extent) << ",\n";
  j << "  \"ate_over_path_percent\": " << jsonNumber(100 * ate.rmseOverPath) << ",\n";
  j << "  \"ate_over_extent_percent\": " << jsonNumber(100 * ate.rmseOverExtent) << ",\n";
  j << "  \"rotation_rmse_deg\": " << jsonNumber(ate.rotationRmseDeg);
  if (rpe)
  {
    j << ",\n  \"rpe_delta\": " << rpe->delta << ",\n";
    j << "  \"rpe_n\": " << rpe->nPairs << ",\n";
    j << "  \"rpe_translation_rmse\": " << jsonNumber(rpe->translationRmse) << ",\n";
    j << "  \"rpe_rotation_rmse_deg\": " << jsonNumber(rpe->rotationRmseDeg) << ",\n";
    j << "  \"rpe_direction_n\": " << rpe->nDirections << ",\n";
    j << "  \"rpe_direction_median_deg\": " << jsonNumber(rpe->directionMedianDeg) << ",\n";
    j << "  \"rpe_direction_rmse_deg\": " << jsonNumber(rpe->directionRmseDeg) << ",\n";
    j << "  \"rpe_scale_ratio_median\": " << jsonNumber(rpe->scaleRatioMedian) << ",\n";
    j << "  \"rpe_scale_ratio_p10\": " << jsonNumber(rpe->scaleRatioP10) << ",\n";
    j << "  \"rpe_scale_ratio_p90\": " << jsonNumber(rpe->scaleRatioP90) << ",\n";
    j << "  \"rpe_scale_log_rms\": " << jsonNumber(rpe->scaleLogRms);
  }
  j << "\n}\n";
  return j.str();
}

/** The text report: one "name: value" line a figure. */
std::string textReport(const TAppOptions& o, std::size_t nEst, std::size_t nGt, const TAteResult& ate,
                       const std::optional<TRpeResult>& rpe)
{
  std::ostringstream s;
  s.imbue(std::locale::classic());
  const auto row = [&](const char* name) -> std::ostream& { return s << std::left << std::setw(22) << name << ": "; };
  const auto num = [](double v) {
    std::ostringstream n;
    n.imbue(std::locale::classic());
    n << std::setprecision(6) << v;
    return n.str();
  };
  row("estimate") << o.estPath << " (" << nEst << " poses)\n";
  row("ground truth") << o.gtPath << " (" << nGt << " poses)\n";
  row("alignment") << alignmentName(o.alignment) << " (max dt " << num(o.maxDt) << " s)\n";
  row("pairs") << ate.nPairs << "\n";
  row("ATE rmse") << num(ate.rmse) << "\n";
  row("ATE mean") << num(ate.mean) << "\n";
  row("ATE median") << num(ate.median) << "\n";
  row("ATE max") << num(ate.max) << "\n";
  row("scale") << num(ate.scale) << (ate.alignmentRank < 2 ? "  (degenerate alignment)" : "") << "\n";
  row("path length") << num(ate.pathLength) << "\n";
  row("extent") << num(ate.extent) << "\n";
  row("ATE / path") << num(100 * ate.rmseOverPath) << " %\n";
  row("ATE / extent") << num(100 * ate.rmseOverExtent) << " %\n";
  row("rotation RMSE") << num(ate.rotationRmseDeg) << " deg\n";
  if (rpe)
  {
    row("RPE delta") << rpe->delta << " (" << rpe->nPairs << " motions)\n";
    row("RPE translation rmse") << num(rpe->translationRmse) << "\n";
    row("RPE rotation rmse") << num(rpe->rotationRmseDeg) << " deg\n";
    row("RPE direction") << "median " << num(rpe->directionMedianDeg) << " deg, rmse " << num(rpe->directionRmseDeg)
                         << " deg (" << rpe->nDirections << " motions >= " << num(rpe->minMotion) << ")\n";
    row("RPE local scale") << "median " << num(rpe->scaleRatioMedian) << ", 10-90 % " << num(rpe->scaleRatioP10) << " - "
                           << num(rpe->scaleRatioP90) << ", log rms " << num(rpe->scaleLogRms) << " (same motions)\n";
  }
  return s.str();
}
}  // namespace

std::string evalAppUsage(const std::string& prog)
{
  return "Usage: " + prog +
         " EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA [--rpe-csv F]] [--json]\n"
         "Absolute trajectory error of an estimated trajectory against ground truth (both TUM\n"
         "format: 'timestamp tx ty tz qx qy qz qw'). Poses are associated by nearest timestamp,\n"
         "the estimate is aligned to the ground truth, and position errors are reported in\n"
         "ground-truth units.\n"
         "  --sim3       align with rotation, translation and scale (default; monocular)\n"
         "  --se3        align with rotation and translation only\n"
         "  --no-align   no alignment\n"
         "  --max-dt S   largest timestamp difference of an associated pair, seconds (default 0.01)\n"
         "  --rpe DELTA  also report the relative pose error over DELTA associated frames\n"
         "  --rpe-csv F  write each of those relative motions' errors to the CSV file F (t_start,\n"
         "               t_end, translation_error, rotation_error_deg, direction_error_deg,\n"
         "               local_scale): where along the run the estimate went wrong\n"
         "  --json       print one JSON object instead of text\n"
         "  --help       this text\n"
         "Exit status: 0 success, 1 bad input, 2 bad usage.\n";
}

int runEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  const std::string prog = args.empty() ? "slam-eval ate" : args[0];
  TAppOptions o;
  try
  {
    o = parseArgs(args);
  }
  catch (const TUsageError& e)
  {
    err << prog << ": " << e.what() << "\n" << evalAppUsage(prog);
    return 2;
  }
  if (o.help)
  {
    out << evalAppUsage(prog);
    return 0;
  }

  TAteResult ate;
  std::optional<TRpeResult> rpe;
  size_t nEst = 0, nGt = 0;
  try
  {
    const core::TTrajectory est = readNonEmpty(o.estPath);
    const core::TTrajectory gt = readNonEmpty(o.gtPath);
    nEst = est.size();
    nGt = gt.size();
    try
    {
      ate = computeAte(est, gt, o.alignment, o.maxDt);
      if (o.rpeDelta > 0) rpe = computeRpe(est, gt, o.rpeDelta, o.alignment, o.maxDt);
    }
    catch (const std::runtime_error& e)
    {
      throw std::runtime_error(o.estPath + " vs " + o.gtPath + ": " + e.what());
    }
    if (!o.rpeCsvPath.empty()) writeRpeCsv(o.rpeCsvPath, *rpe);
  }
  catch (const std::exception& e)
  {
    err << prog << ": " << e.what() << "\n";
    return 1;
  }

  if (o.json)
  {
    out << jsonReport(o, nEst, nGt, ate, rpe);
    return 0;
  }

  out << textReport(o, nEst, nGt, ate, rpe);
  return 0;
}
}  // namespace immslam::evalapp

/* imm-monoslam — static/dynamic decisions against masks or ground-truth points. */
#include <immslam/eval/classification_truth.h>

#include "table_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace immslam::eval
{
std::vector<TClassificationDecision> readClassificationsCsv(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Comma, "classifications file");
  std::vector<TClassificationDecision> out;
  static const std::vector<std::string> kHead{"timestamp", "feature_id", "class", "u", "v"};
  if (!r.next()) throw std::runtime_error(path + ": empty file (expected a header 'timestamp,feature_id,class,u,v')");
  if (r.fields().size() < kHead.size() || !std::equal(kHead.begin(), kHead.end(), r.fields().begin()))
    r.fail("expected a header starting 'timestamp,feature_id,class,u,v'");
  const std::size_t nCols = r.fields().size();
  while (r.next())
  {
    if (r.fields().size() != nCols)
      r.fail("expected " + std::to_string(nCols) + " fields like the header, got " + std::to_string(r.fields().size()));
    TClassificationDecision d;
    d.timestamp = r.number(0, "timestamp");
    d.featureId = r.integer(1, "feature_id");
    const std::string& c = r.fields()[2];
    if (c == "static")
      d.decided = EMotionClass::Static;
    else if (c == "dynamic")
      d.decided = EMotionClass::Dynamic;
    else
      r.fail("unknown class '" + c + "' (expected static or dynamic)");
    d.uv = Vec2(r.number(3, "u"), r.number(4, "v"));
    out.push_back(d);
  }
  return out;
}

std::string TClassificationResult::summary() const
{
  return confusion.summary() + "  unmatched decisions : " + std::to_string(unmatched) + " (no ground truth)\n";
}

std::ostream& operator<<(std::ostream& os, const TClassificationResult& r) { return os << r.summary(); }

TClassificationResult evaluateClassifications(const std::vector<TClassificationDecision>& decisions,
                                              const TClassificationTruth& truth)
{
  TClassificationResult r;
  for (const auto& d : decisions)
  {
    if (const std::optional<EMotionClass> t = truth(d))
      r.confusion.add(*t, d.decided);
    else
      ++r.unmatched;
  }
  return r;
}

TMaskImage TMaskImage::fromBuffer(const std::uint8_t* data, int width, int height, std::size_t strideBytes)
{
  if (width < 0 || height < 0 || (width > 0 && height > 0 && (!data || strideBytes < static_cast<std::size_t>(width))))
    throw std::invalid_argument("TMaskImage::fromBuffer: bad size, stride or null data");
  TMaskImage m;
  m.width = width;
  m.height = height;
  m.pixels.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int v = 0; v < height; ++v)
    if (width > 0)
      std::memcpy(m.pixels.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(width),
                  data + static_cast<std::size_t>(v) * strideBytes, static_cast<std::size_t>(width));
  return m;
}

bool TMaskImage::movingNear(const Vec2& uv, int radius) const
{
  if (!uv.allFinite()) return false;
  const double lim = 1e9;  // keep lround in range for absurd pixels
  const long u = std::lround(std::clamp(uv.x(), -lim, lim)), v = std::lround(std::clamp(uv.y(), -lim, lim));
  for (long dv = -radius; dv <= radius; ++dv)
    for (long du = -radius; du <= radius; ++du)
      if (u + du >= 0 && v + dv >= 0 && u + du < width && v + dv < height &&
          at(static_cast<int>(u + du), static_cast<int>(v + dv)) > 0)
        return true;
  return false;
}

TClassificationResult classificationAgainstMasks(const std::vector<TClassificationDecision>& decisions,
                                                 const TMaskProvider& maskAt, int radius)
{
  if (radius < 0) throw std::invalid_argument("classificationAgainstMasks: radius must be >= 0");
  bool haveLast = false;
  double lastT = 0;
  std::optional<TMaskImage> mask;
  return evaluateClassifications(decisions, [&](const TClassificationDecision& d) -> std::optional<EMotionClass> {
    if (!haveLast || d.timestamp != lastT)
    {
      mask = maskAt(d.timestamp);
      lastT = d.timestamp;
      haveLast = true;
    }
    if (!mask) return std::nullopt;
    return mask->movingNear(d.uv, radius) ? EMotionClass::Dynamic : EMotionClass::Static;
  });
}

TMaskProvider maskFolderProvider(const std::string& datasetFolder, double maxDt)
{
  namespace fs = std::filesystem;
  const fs::path dir(datasetFolder);
  const fs::path rgbTxt = dir / "rgb.txt";
  if (!fs::is_directory(dir / "masks"))
    throw std::runtime_error((dir / "masks").string() + ": no masks folder (not a rendered data set?)");
  // rgb.txt: timestamp -> mask file, sorted by time.
  std::vector<std::pair<double, std::string>> entries;
  {
    detail::CTableReader r(rgbTxt.string(), detail::CTableReader::ESeparator::Whitespace, "image list");
    while (r.next())
    {
      r.requireFields(2, "timestamp filename");
      entries.emplace_back(r.number(0, "timestamp"), (dir / "masks" / fs::path(r.fields()[1]).filename()).string());
    }
  }
  std::stable_sort(entries.begin(), entries.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<double> times(entries.size());
  for (std::size_t i = 0; i < entries.size(); ++i) times[i] = entries[i].first;
  return [entries = std::move(entries), times = std::move(times), maxDt](double t) -> std::optional<TMaskImage> {
    const std::ptrdiff_t i = detail::nearestTime(times, t, maxDt);
    if (i < 0) return std::nullopt;
    return readMaskImage(entries[static_cast<std::size_t>(i)].second);
  };
}

TClassificationResult classificationAgainstMaskFolder(const std::vector<TClassificationDecision>& decisions,
                                                      const std::string& datasetFolder, int radius, double maxDt)
{
  return classificationAgainstMasks(decisions, maskFolderProvider(datasetFolder, maxDt), radius);
}

std::vector<core::TGroundTruthPoint> readPointsGroundTruth(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Whitespace, "ground-truth points file");
  std::vector<core::TGroundTruthPoint> out;
  while (r.next())
  {
    r.requireFields(8, "timestamp point_id kind x y z u v");
    core::TGroundTruthPoint p;
    p.timestamp = r.number(0, "timestamp");
    p.pointId = r.integer(1, "point_id");
    const std::string& kind = r.fields()[2];
    if (kind == "moving")
      p.moving = true;
    else if (kind != "static")
      r.fail("unknown kind '" + kind + "' (expected static or moving)");
    p.p_W = Vec3(r.number(3, "x"), r.number(4, "y"), r.number(5, "z"));
    p.uv = Vec2(r.number(6, "u"), r.number(7, "v"));
    out.push_back(p);
  }
  return out;
}

namespace
{
/** Ground-truth points grouped by frame time, for nearest-pixel lookups. */
class CPointsByFrame
{
 public:
  explicit CPointsByFrame(const std::vector<core::TGroundTruthPoint>& points) : m_points(points), m_order(points.size())
  {
    // Sorted by time (stable: file order within a frame), with the distinct frame times.
    std::iota(m_order.begin(), m_order.end(), std::size_t{0});
    std::stable_sort(m_order.begin(), m_order.end(),
                     [&](std::size_t a, std::size_t b) { return points[a].timestamp < points[b].timestamp; });
    for (std::size_t i = 0; i < m_order.size(); ++i)
      if (m_times.empty() || points[m_order[i]].timestamp != m_times.back())
        m_times.push_back(points[m_order[i]].timestamp), m_start.push_back(i);
    m_start.push_back(m_order.size());
  }

  /** The point of the frame within maxDt of t whose projection is nearest to uv, if at most
   * radiusPx away; null otherwise. */
  const core::TGroundTruthPoint* nearest(double t, const Vec2& uv, double radiusPx, double maxDt) const
  {
    const std::ptrdiff_t f = detail::nearestTime(m_times, t, maxDt);
    if (f < 0) return nullptr;
    double best = std::numeric_limits<double>::infinity();
    const core::TGroundTruthPoint* found = nullptr;
    for (std::size_t i = m_start[static_cast<std::size_t>(f)]; i < m_start[static_cast<std::size_t>(f) + 1]; ++i)
    {
      const core::TGroundTruthPoint& p = m_points[m_order[i]];
      if (const double dist = std::hypot(p.uv.x() - uv.x(), p.uv.y() - uv.y()); dist < best) best = dist, found = &p;
    }
    return best <= radiusPx ? found : nullptr;
  }

 private:
  const std::vector<core::TGroundTruthPoint>& m_points;
  std::vector<std::size_t> m_order;
  std::vector<double> m_times;
  std::vector<std::size_t> m_start;  // index into m_order of each frame's first point, + end
};
}  // namespace

TClassificationResult classificationAgainstPoints(const std::vector<TClassificationDecision>& decisions,
                                                  const std::vector<core::TGroundTruthPoint>& points, double radiusPx,
                                                  double maxDt)
{
  if (!(radiusPx >= 0)) throw std::invalid_argument("classificationAgainstPoints: radius must be >= 0 px");
  const CPointsByFrame byFrame(points);
  return evaluateClassifications(decisions, [&](const TClassificationDecision& d) -> std::optional<EMotionClass> {
    const core::TGroundTruthPoint* p = byFrame.nearest(d.timestamp, d.uv, radiusPx, maxDt);
    if (!p) return std::nullopt;
    return p->moving ? EMotionClass::Dynamic : EMotionClass::Static;
  });
}

std::vector<core::TTrackSample> readTracksCsv(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Comma, "tracks file");
  std::vector<core::TTrackSample> out;
  static const std::vector<std::string> kHead{"timestamp", "feature_id", "x", "y", "z", "u", "v"};
  if (!r.next()) throw std::runtime_error(path + ": empty file (expected a header 'timestamp,feature_id,x,y,z,u,v')");
  if (r.fields().size() < kHead.size() || !std::equal(kHead.begin(), kHead.end(), r.fields().begin()))
    r.fail("expected a header starting 'timestamp,feature_id,x,y,z,u,v'");
  const std::size_t nCols = r.fields().size();
  const auto column = [&](const std::string& name) {
    const auto it = std::find(r.fields().begin() + static_cast<std::ptrdiff_t>(kHead.size()), r.fields().end(), name);
    return it == r.fields().end() ? std::size_t{0} : static_cast<std::size_t>(it - r.fields().begin());
  };
  const std::size_t iRange = column("range"), iSigma = column("range_rel_sigma");
  while (r.next())
  {
    if (r.fields().size() != nCols)
      r.fail("expected " + std::to_string(nCols) + " fields like the header, got " + std::to_string(r.fields().size()));
    core::TTrackSample t;
    if (iRange) t.range = r.number(iRange, "range");
    if (iSigma) t.rangeRelSigma = r.number(iSigma, "range_rel_sigma");
    t.timestamp = r.number(0, "timestamp");
    t.featureId = r.integer(1, "feature_id");
    t.p_W = Vec3(r.number(2, "x"), r.number(3, "y"), r.number(4, "z"));
    t.uv = Vec2(r.number(5, "u"), r.number(6, "v"));
    out.push_back(t);
  }
  return out;
}

std::string TTrackErrorResult::summary() const
{
  std::ostringstream s;
  s << "track samples : " << samples << " (" << tracks << " tracks)\n"
    << "on a moving ground-truth point : " << matched << " samples of " << matchedTracks << " tracks\n"
    << "on a static ground-truth point : " << onStatic << "\n"
    << "no ground-truth point near     : " << unmatched << "\n";
  if (std::isfinite(maxRelativeSigma))
    s << "left out (range_rel_sigma > " << maxRelativeSigma << "): " << uncertain << " of the moving-point samples\n";
  if (matched > 0)
    s << "position error (after the camera's alignment): RMS " << rmse << ", median " << median << ", max " << max
      << " (ground-truth units)\n";
  if (matched > 0 && std::isfinite(medianRange))
    s << "median distance of those points from the camera: " << medianRange << "\n";
  return s.str();
}

TTrackErrorResult trackErrorAgainstPoints(const std::vector<core::TTrackSample>& samples,
                                          const std::vector<core::TGroundTruthPoint>& points, const TSim3& alignment,
                                          double radiusPx, double maxDt, double maxRelativeSigma)
{
  if (!(radiusPx >= 0)) throw std::invalid_argument("trackErrorAgainstPoints: radius must be >= 0 px");
  if (!(maxRelativeSigma > 0)) throw std::invalid_argument("trackErrorAgainstPoints: relative sigma limit must be > 0");
  const CPointsByFrame byFrame(points);
  TTrackErrorResult r;
  r.samples = samples.size();
  r.maxRelativeSigma = maxRelativeSigma;
  std::set<std::int64_t> all, matchedIds;
  std::vector<double> err, range;
  for (const core::TTrackSample& t : samples)
  {
    all.insert(t.featureId);
    const core::TGroundTruthPoint* p = byFrame.nearest(t.timestamp, t.uv, radiusPx, maxDt);
    if (!p)
      ++r.unmatched;
    else if (!p->moving)
      ++r.onStatic;
    else if (std::isfinite(maxRelativeSigma) && !(t.rangeRelSigma <= maxRelativeSigma))
      ++r.uncertain;
    else
    {
      err.push_back((alignment.transform(t.p_W) - p->p_W).norm());
      if (std::isfinite(t.range)) range.push_back(alignment.s * t.range);
      matchedIds.insert(t.featureId);
    }
  }
  r.tracks = all.size();
  r.matched = err.size();
  r.matchedTracks = matchedIds.size();
  if (!err.empty())
  {
    double sq = 0;
    for (const double e : err) sq += e * e;
    r.rmse = std::sqrt(sq / static_cast<double>(err.size()));
    r.max = *std::max_element(err.begin(), err.end());
    std::nth_element(err.begin(), err.begin() + static_cast<std::ptrdiff_t>(err.size() / 2), err.end());
    r.median = err[err.size() / 2];
  }
  if (!range.empty())
  {
    std::nth_element(range.begin(), range.begin() + static_cast<std::ptrdiff_t>(range.size() / 2), range.end());
    r.medianRange = range[range.size() / 2];
  }
  return r;
}
}  // namespace immslam::eval

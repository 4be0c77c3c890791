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

TClassificationResult classificationAgainstMaskFolder(const std::vector<TClassificationDecision>& decisions,
                                                      const std::string& datasetFolder, int radius, double maxDt)
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
  return classificationAgainstMasks(
      decisions,
      [&](double t) -> std::optional<TMaskImage> {
        const std::ptrdiff_t i = detail::nearestTime(times, t, maxDt);
        if (i < 0) return std::nullopt;
        return readMaskImage(entries[static_cast<std::size_t>(i)].second);
      },
      radius);
}

std::vector<TGroundTruthPoint> readPointsGroundTruth(const std::string& path)
{
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Whitespace, "ground-truth points file");
  std::vector<TGroundTruthPoint> out;
  while (r.next())
  {
    r.requireFields(8, "timestamp point_id kind x y z u v");
    TGroundTruthPoint p;
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

TClassificationResult classificationAgainstPoints(const std::vector<TClassificationDecision>& decisions,
                                                  const std::vector<TGroundTruthPoint>& points, double radiusPx,
                                                  double maxDt)
{
  if (!(radiusPx >= 0)) throw std::invalid_argument("classificationAgainstPoints: radius must be >= 0 px");
  // Points sorted by time (stable: file order within a frame), with the distinct frame times.
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return points[a].timestamp < points[b].timestamp; });
  std::vector<double> frameTimes;
  std::vector<std::size_t> frameStart;  // index into order
  for (std::size_t i = 0; i < order.size(); ++i)
    if (frameTimes.empty() || points[order[i]].timestamp != frameTimes.back())
      frameTimes.push_back(points[order[i]].timestamp), frameStart.push_back(i);
  frameStart.push_back(order.size());

  return evaluateClassifications(decisions, [&](const TClassificationDecision& d) -> std::optional<EMotionClass> {
    const std::ptrdiff_t f = detail::nearestTime(frameTimes, d.timestamp, maxDt);
    if (f < 0) return std::nullopt;
    double best = std::numeric_limits<double>::infinity();
    bool moving = false;
    for (std::size_t i = frameStart[static_cast<std::size_t>(f)]; i < frameStart[static_cast<std::size_t>(f) + 1]; ++i)
    {
      const TGroundTruthPoint& p = points[order[i]];
      if (const double dist = std::hypot(p.uv.x() - d.uv.x(), p.uv.y() - d.uv.y()); dist < best)
        best = dist, moving = p.moving;
    }
    if (!(best <= radiusPx)) return std::nullopt;
    return moving ? EMotionClass::Dynamic : EMotionClass::Static;
  });
}
}  // namespace immslam::eval

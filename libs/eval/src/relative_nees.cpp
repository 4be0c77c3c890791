/* imm-monoslam — NEES of the SLAM filter's relative poses (relative_poses.csv). */
#include <immslam/eval/relative_nees.h>

#include <immslam/eval/consistency.h>
#include <immslam/eval/statistics.h>
#include <immslam/math/chi2.h>
#include <immslam/math/quaternion.h>

#include "table_reader.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace immslam::eval
{
std::vector<TRelativePoseRow> readRelativePosesCsv(const std::string& path)
{
  std::vector<std::string> head{"timestamp", "from_timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) head.push_back("c" + std::to_string(i) + std::to_string(j));
  detail::CTableReader r(path, detail::CTableReader::ESeparator::Comma, "relative poses file");
  if (!r.next()) throw std::runtime_error(path + ": empty file (expected a header 'timestamp,from_timestamp,tx,...,c55')");
  if (r.fields() != head) r.fail("expected the header 'timestamp,from_timestamp,tx,ty,tz,qx,qy,qz,qw,c00,c01,...,c55'");
  std::vector<TRelativePoseRow> out;
  while (r.next())
  {
    if (r.fields().size() != head.size())
      r.fail("expected " + std::to_string(head.size()) + " fields like the header, got " +
             std::to_string(r.fields().size()));
    TRelativePoseRow row;
    row.timestamp = r.number(0, "timestamp");
    row.fromTimestamp = r.number(1, "from_timestamp");
    row.t = Vec3(r.number(2, "tx"), r.number(3, "ty"), r.number(4, "tz"));
    const Vec4 q(r.number(8, "qw"), r.number(5, "qx"), r.number(6, "qy"), r.number(7, "qz"));
    if (!(q.norm() > 0)) r.fail("zero quaternion");
    row.q = q.normalized();
    std::size_t c = 9;
    for (int i = 0; i < 6; ++i)
      for (int j = i; j < 6; ++j, ++c) row.cov(i, j) = row.cov(j, i) = r.number(c, head[c]);
    out.push_back(row);
  }
  return out;
}

TRelativeNeesResult computeRelativeNees(const std::vector<TRelativePoseRow>& rows, const core::TTrajectory& gt,
                                        double scale, double maxDt, double confidence)
{
  if (!(confidence > 0 && confidence < 1)) throw std::invalid_argument("computeRelativeNees: confidence in (0, 1)");
  if (!(maxDt >= 0)) throw std::invalid_argument("computeRelativeNees: maxDt >= 0");
  TRelativeNeesResult res;
  res.nRows = rows.size();
  res.confidence = confidence;
  res.scale = scale > 0 ? scale : 0;
  std::vector<std::size_t> order(gt.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return gt[a].timestamp < gt[b].timestamp; });
  std::vector<double> times;
  for (std::size_t i : order) times.push_back(gt[i].timestamp);
  for (const auto& row : rows)
  {
    const auto a = detail::nearestTime(times, row.fromTimestamp, maxDt);
    const auto b = detail::nearestTime(times, row.timestamp, maxDt);
    if (a < 0 || b < 0) continue;
    const auto& pj = gt[order[static_cast<std::size_t>(a)]];
    const auto& pk = gt[order[static_cast<std::size_t>(b)]];
    // True T_{C_j C_k} and the error [t - t_hat; Log(R_hat^T R)] in the row's convention.
    const Vec4 q = math::quatMultiply(math::quatConjugate(pj.q_W_C), pk.q_W_C);
    Vec6 e;
    e.tail<3>() = math::quatToRotationVector(math::quatMultiply(math::quatConjugate(row.q), q));
    ++res.nUsed;
    res.rotation.push_back(nees(e.tail<3>(), row.cov.bottomRightCorner<3, 3>()));
    if (res.scale > 0)
    {
      const Vec3 t = math::quatToRotation(pj.q_W_C).transpose() * (pk.p_W_C - pj.p_W_C) / res.scale;
      e.head<3>() = t - row.t;
      res.full.push_back(nees(e, row.cov));
    }
  }
  return res;
}

std::string TRelativeNeesResult::summary() const
{
  std::string s;
  char buf[256];
  std::snprintf(buf, sizeof buf, "relative poses : %zu rows, %zu with ground truth at both ends\n", nRows, nUsed);
  s += buf;
  const auto line = [&](const char* what, const std::vector<double>& v, int dof) {
    if (v.empty()) return;
    const double bound = math::chi2Quantile(confidence, dof);
    const auto inside = std::count_if(v.begin(), v.end(), [bound](double x) { return x <= bound; });
    std::snprintf(buf, sizeof buf,
                  "%-14s : NEES mean %.3f (consistent: %d), median %.3f (%.3f), inside the %.0f %% bound %.2f: "
                  "%.1f %% of the rows\n",
                  what, eval::mean(v), dof, median(v), math::chi2Quantile(0.5, dof), 100 * confidence, bound,
                  100.0 * static_cast<double>(inside) / static_cast<double>(v.size()));
    s += buf;
  };
  line("rotation", rotation, 3);
  if (scale > 0)
  {
    std::snprintf(buf, sizeof buf, "map scale      : %.6g ground-truth units per map unit\n", scale);
    s += buf;
    line("full pose", full, 6);
  }
  else
    s += "full pose      : not computed (give the run's trajectory for the map's scale)\n";
  return s;
}
}  // namespace immslam::eval

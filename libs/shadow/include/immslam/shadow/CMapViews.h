/* imm-monoslam — the SLAM map's measured pixels over recent frames: the reference that the shadow
 * filter's three-ray test of a pending feature is compared with over the same views. */
#pragma once

#include <immslam/math/types.h>

#include <array>
#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

namespace immslam::shadow
{
/** Pixels at which the SLAM filter measured its map's features (its inliers: points the static
 * world's consensus holds static) in each of the last kFrames frames. */
class CMapViews
{
 public:
  /** Frames kept (the shadow filter's longest pending life, [shadow] max_pending_frames). */
  static constexpr std::size_t kFrames = 160;

  /** Records frame `frame`'s measurements (id, pixel); frames must come in increasing order. */
  void add(std::int64_t frame, std::vector<std::pair<std::int64_t, Vec2>> z);
  /** Pixels of up to maxCount features measured in all three frames (spread evenly over their ids). */
  std::vector<std::array<Vec2, 3>> common(const std::array<std::int64_t, 3>& frames, std::size_t maxCount) const;
  bool empty() const { return m_frames.empty(); }
  void clear() { m_frames.clear(); }

 private:
  using TFrame = std::pair<std::int64_t, std::vector<std::pair<std::int64_t, Vec2>>>;
  const TFrame* find(std::int64_t frame) const;
  std::deque<TFrame> m_frames;  ///< oldest first; each frame's measurements sorted by id
};
}  // namespace immslam::shadow

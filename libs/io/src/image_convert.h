/* imm-monoslam — private helpers of libs/io: turning decoded images into TFrame pixels. */
#pragma once

#include <immslam/io/CImageSource.h>

#include <opencv2/core/mat.hpp>

#include <string>

namespace immslam::io::detail
{
/** Fills frame.grey (CV_8UC1) and frame.colour (CV_8UC3 BGR, or empty for grey input) from an
 * image as decoded by cv::imread(IMREAD_UNCHANGED): 1 channel = grey, 2 = grey + alpha,
 * 3 = BGR, 4 = BGRA; 8- or 16-bit (16-bit values are divided by 256).
 * \return false (with `why`) for an empty image or an unsupported type. */
bool setFrameImages(const cv::Mat& raw, TFrame& frame, std::string& why);

/** cv::imread(path, IMREAD_UNCHANGED) then setFrameImages(). On failure `why` names the file and
 * tells whether it is missing or undecodable. */
bool loadFrameImages(const std::string& path, TFrame& frame, std::string& why);

/** Text of an exception for a one-line message: whitespace runs (MRPT's multi-line stacked
 * messages) collapsed to single spaces, trimmed. */
std::string oneLine(const std::string& text);

/** The messages of an MRPT (possibly stacked) exception text, outermost first, joined by ": ",
 * without locations and call stacks; any other text is returned as oneLine(). */
std::string mrptMessage(const std::string& text);
}  // namespace immslam::io::detail

/* imm-monoslam fuzz targets: private helpers. */
#pragma once

#include "fuzz_targets.h"

#include <exception>
#include <string>

namespace immslam::fuzz
{
/** Writes bytes to a file (truncating it). */
void writeFile(const std::string& path, const std::string& bytes);

/** A property of the code under test does not hold: prints it and aborts (the fuzzer's "crash"). */
[[noreturn]] void fail(const std::string& what);

/** Errors must name the file, line or key at fault: fail() unless e.what() contains `name`. */
void requireMentions(const std::exception& e, const std::string& name, const std::string& target);
}  // namespace immslam::fuzz

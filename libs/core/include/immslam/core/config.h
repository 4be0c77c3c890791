/* imm-monoslam — strict configuration reading on top of mrpt::config.
 *
 * MRPT's read_double() silently turns "abc" into 0 and its parser ignores unknown keys; users of
 * imm-monoslam get an error that names the section, the key and the bad value instead. Options
 * classes (mrpt::config::CLoadableOptions) load their members with IMMSLAM_LOAD_* (the member name
 * is the ini key, as with MRPT_LOAD_CONFIG_VAR) and save them with MRPT_SAVE_CONFIG_VAR_COMMENT. */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/config/CLoadableOptions.h>

#include <set>
#include <string>
#include <vector>

namespace immslam::core
{
/** Reads a key as a number; the default when absent. \throws std::runtime_error
 * "[section] key = 'value': not a number" for anything that does not parse completely. */
double readDouble(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, double def);
int readInt(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, int def);
bool readBool(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key, bool def);
std::string readString(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::string& key,
                       const std::string& def);
/** A list of numbers "[1 2 3]" or "1, 2, 3"; the default when absent. */
std::vector<double> readVector(const mrpt::config::CConfigFileBase& c, const std::string& section,
                               const std::string& key, const std::vector<double>& def);

/** The keys an options object knows in `section`: those its saveToConfigFile() writes. */
std::set<std::string> knownKeys(const mrpt::config::CLoadableOptions& opts, const std::string& section);

/** \throws std::runtime_error naming every key of `section` in `c` that is not in `known`
 * (with the closest known key as a hint). No-op if the section does not exist. */
void checkKnownKeys(const mrpt::config::CConfigFileBase& c, const std::string& section, const std::set<std::string>& known);

/** Checks the syntax of ini text before it is handed to MRPT's parser, which silently drops what it
 * cannot parse (a line `sigma_pixel 2` without '=', a key before the first section, `= 2`), so that
 * a mistyped line is an error instead of a default value. Accepted lines: blank; comments (first
 * non-blank characters `#`, `;` or `//`); `[section]` (optionally followed by a comment); MRPT
 * preprocessor lines (`@define ...`, first non-blank character `@`); `key = value` inside a section,
 * each key at most once per section (MRPT keeps only one of them).
 * \param origin the file name used in errors: "origin:LINE: ...".
 * \throws std::runtime_error naming origin:line and the offending text (the first problem only). */
void checkIniSyntax(const std::string& text, const std::string& origin);

/** Value checks with errors naming section.key. */
void requirePositive(double v, const std::string& section, const std::string& key);
void requireNonNegative(double v, const std::string& section, const std::string& key);
void requireInRange(double v, double lo, double hi, const std::string& section, const std::string& key);
}  // namespace immslam::core

/** Loads member `var` (key "var") of an options struct inside loadFromConfigFile(c, s). */
#define IMMSLAM_LOAD_DOUBLE(var) var = immslam::core::readDouble(c, s, #var, var)
#define IMMSLAM_LOAD_INT(var) var = immslam::core::readInt(c, s, #var, var)
#define IMMSLAM_LOAD_BOOL(var) var = immslam::core::readBool(c, s, #var, var)
#define IMMSLAM_LOAD_STRING(var) var = immslam::core::readString(c, s, #var, var)
#define IMMSLAM_LOAD_VECTOR(var) var = immslam::core::readVector(c, s, #var, var)

// Minimal leveled logging to stderr. VXR_LOG=debug|info|warn|error sets the floor.
#pragma once

#include <cstdio>
#include <string>

namespace vxr {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

void set_log_level(LogLevel level);
LogLevel log_level();
void log_message(LogLevel level, const std::string& text);

inline void log_debug(const std::string& t) { log_message(LogLevel::kDebug, t); }
inline void log_info(const std::string& t) { log_message(LogLevel::kInfo, t); }
inline void log_warn(const std::string& t) { log_message(LogLevel::kWarn, t); }
inline void log_error(const std::string& t) { log_message(LogLevel::kError, t); }

}  // namespace vxr

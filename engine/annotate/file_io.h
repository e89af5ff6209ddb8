// Whole-file reads for annotation inputs (SWC, scripts, media).
#pragma once

#include <string>

#include "core/status.h"

namespace vxr::annotate {

// The file's bytes; errors name the path ("<path>: no such file", ...).
Result<std::string> read_whole_file(const std::string& path);
// Writes go through vxr::write_file_atomically (core/output_file.h).

}  // namespace vxr::annotate

// Whole-file reads and atomic writes for annotation inputs and exports.
#pragma once

#include <string>

#include "core/status.h"

namespace vxr::annotate {

// The file's bytes; errors name the path ("<path>: no such file", ...).
Result<std::string> read_whole_file(const std::string& path);
// Writes "<path>.partial", fsyncs, renames over `path`: readers never see half a file.
Status write_file_atomic(const std::string& path, const std::string& bytes);

}  // namespace vxr::annotate

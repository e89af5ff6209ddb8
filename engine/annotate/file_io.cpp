#include "annotate/file_io.h"

#include "core/output_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace vxr::annotate {

Result<std::string> read_whole_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec))  // a FIFO would block the read forever
    if (Status st = check_input(path); !st.is_ok()) return st;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    if (err == ENOENT) return not_found(path + ": no such file");
    return io_error(path + ": cannot open (" + std::strerror(err) + ")");
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return io_error(path + ": read failed");
  return ss.str();
}

}  // namespace vxr::annotate

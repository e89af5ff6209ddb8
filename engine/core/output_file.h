// How vxr writes an output without harming anything that is already there.
//
// Outputs never touch inputs: check_output refuses an output path that is (or
// resolves to) one of the inputs, a directory, or an existing file that is not
// a regular file (device node, FIFO, socket). The data then goes to a fresh
// temp file beside the target (created O_EXCL|O_NOFOLLOW, so a planted file or
// symlink is never followed or reused) and is renamed over the target only
// when complete: a reader never sees a half-written file under the final name.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr {

// Refuses `output` when it names an input (same file, through any symlink or
// hard link), a directory, or an existing non-regular file; also when its
// folder does not exist. `role` names the option in messages ("-o").
Status check_output(const std::string& output, std::span<const std::string> inputs, const std::string& role = "output");

// Refuses an input that is not a regular file (a FIFO would block the reader
// forever, a device could be endless). Directories pass when `allow_dir`.
Status check_input(const std::string& input, bool allow_dir = false);

// A temp file beside `target`, removed on destruction unless committed.
class TempFile {
 public:
  // Creates "<dir>/.<name>.XXXXXX.partial" with O_CREAT|O_EXCL|O_NOFOLLOW, mode 0644 less the umask.
  static Result<TempFile> create_beside(const std::string& target);
  TempFile() = default;
  TempFile(TempFile&& other) noexcept;
  TempFile& operator=(TempFile&& other) noexcept;
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile();

  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  const std::string& target() const { return target_; }

  // Writes all of `bytes` at the current position.
  Status write(std::span<const uint8_t> bytes);
  Status write(const std::string& text) {
    return write(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
  // Hands the descriptor to a library that closes it itself (libtiff, stdio).
  int release_fd();
  // fsync, close, recheck the target (not a directory or special file by now)
  // and rename over it.
  Status commit();

 private:
  void discard();
  int fd_ = -1;
  std::string path_, target_;
  bool committed_ = false;
};

// Writes `bytes` to `target` through a TempFile: all or nothing.
Status write_file_atomically(const std::string& target, std::span<const uint8_t> bytes);
Status write_file_atomically(const std::string& target, const std::string& text);

}  // namespace vxr

#include "core/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

namespace vxr {
namespace fs = std::filesystem;
namespace {

std::string errno_text() { return std::strerror(errno); }

// What an existing path is, for messages; empty for a regular file.
std::string special_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  if (!S_ISREG(mode)) return "not a regular file";
  return {};
}

fs::path folder_of(const std::string& target) {
  fs::path parent = fs::path(target).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

void fsync_folder(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    (void)::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

Status check_output(const std::string& output, std::span<const std::string> inputs, const std::string& role) {
  if (output.empty()) return invalid_argument(role + ": give a file name");
  struct stat st{};
  if (::stat(output.c_str(), &st) == 0) {  // follows symlinks: what the name resolves to
    if (S_ISDIR(st.st_mode))
      return invalid_argument(role + " '" + output + "' is a folder; give a file name inside it");
    if (const std::string kind = special_kind(st.st_mode); !kind.empty())
      return invalid_argument(role + " '" + output + "' is " + kind + "; vxr writes outputs only to regular files");
    for (const std::string& in : inputs) {
      std::error_code ec;
      if (!in.empty() && fs::equivalent(output, in, ec))
        return invalid_argument(role + " '" + output + "' is also an input ('" + in +
                                "'); writing it would destroy the input: choose another name");
    }
  } else if (errno != ENOENT) {
    return io_error(role + " '" + output + "': " + errno_text());
  }
  std::error_code ec;
  const fs::path folder = folder_of(output);
  if (!fs::is_directory(folder, ec))
    return not_found(role + " '" + output + "': folder '" + folder.string() + "' does not exist");
  // An input folder (an OME-Zarr store, a slice series, an annotation store)
  // is read as a whole: a new file inside it could become a chunk key, a
  // slice or a database file.
  const fs::path out_real = fs::weakly_canonical(fs::absolute(output, ec), ec);
  for (const std::string& in : inputs) {
    if (in.empty() || !fs::is_directory(in, ec)) continue;
    const fs::path dir = fs::canonical(in, ec);
    if (ec) continue;
    auto [d, o] = std::mismatch(dir.begin(), dir.end(), out_real.begin(), out_real.end());
    if (d == dir.end())
      return invalid_argument(role + " '" + output + "' is inside the input folder '" + in +
                              "'; writing there could change the input: choose a path outside it");
  }
  return Status::ok();
}

Status check_input(const std::string& input, bool allow_dir) {
  struct stat st{};
  if (::stat(input.c_str(), &st) != 0) return not_found(input + ": " + errno_text());
  if (allow_dir && S_ISDIR(st.st_mode)) return Status::ok();
  if (const std::string kind = special_kind(st.st_mode); !kind.empty())
    return invalid_argument(input + ": is " + kind + ", not a file vxr can read");
  return Status::ok();
}

Result<TempFile> TempFile::create_beside(const std::string& target) {
  static std::atomic<uint64_t> counter{0};
  std::mt19937_64 rng(std::random_device{}() ^ uint64_t(::getpid()) << 32 ^
                      uint64_t(std::chrono::steady_clock::now().time_since_epoch().count()) ^ counter++);
  const fs::path folder = folder_of(target);
  const std::string name = fs::path(target).filename().string();
  for (int attempt = 0; attempt < 64; ++attempt) {
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "%06llx", static_cast<unsigned long long>(rng() & 0xffffff));
    const std::string path = (folder / (name + "." + suffix + ".partial")).string();
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) {
      TempFile t;
      t.fd_ = fd;
      t.path_ = path;
      t.target_ = target;
      return t;
    }
    if (errno != EEXIST)
      return io_error(target + ": cannot create a temp file in '" + folder.string() + "' (" + errno_text() +
                      "); check that the folder exists and is writable");
  }
  return io_error(target + ": cannot find a free temp file name in '" + folder.string() + "'");
}

TempFile::TempFile(TempFile&& o) noexcept
    : fd_(o.fd_), path_(std::move(o.path_)), target_(std::move(o.target_)), committed_(o.committed_) {
  o.fd_ = -1;
  o.path_.clear();
}

TempFile& TempFile::operator=(TempFile&& o) noexcept {
  if (this != &o) {
    discard();
    fd_ = o.fd_;
    path_ = std::move(o.path_);
    target_ = std::move(o.target_);
    committed_ = o.committed_;
    o.fd_ = -1;
    o.path_.clear();
  }
  return *this;
}

TempFile::~TempFile() { discard(); }

void TempFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!committed_ && !path_.empty()) ::unlink(path_.c_str());
  path_.clear();
}

int TempFile::release_fd() {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

Status TempFile::write(std::span<const uint8_t> bytes) {
  if (fd_ < 0) return internal_error(target_ + ": temp file is not open");
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return io_error(target_ + ": write failed (" + errno_text() + ")");
    }
    done += size_t(n);
  }
  return Status::ok();
}

Status TempFile::commit() {
  if (path_.empty() || committed_) return internal_error(target_ + ": nothing to commit");
  // Data on disk before the name points at it.
  int fd = fd_;
  if (fd < 0) fd = ::open(path_.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  fd_ = -1;
  if (!synced) return io_error(target_ + ": cannot sync " + path_ + " (" + errno_text() + ")");
  // The target may have become a folder or a device since the command started.
  struct stat st{};
  if (::lstat(target_.c_str(), &st) == 0 && !S_ISLNK(st.st_mode) && !special_kind(st.st_mode).empty())
    return invalid_argument(target_ + ": is " + special_kind(st.st_mode) + " now; not replaced");
  if (std::rename(path_.c_str(), target_.c_str()) != 0)
    return io_error(target_ + ": cannot rename " + path_ + " into place (" + errno_text() + ")");
  committed_ = true;
  fsync_folder(folder_of(target_));
  path_.clear();
  return Status::ok();
}

Status write_file_atomically(const std::string& target, std::span<const uint8_t> bytes) {
  VXR_ASSIGN_OR_RETURN(TempFile tmp, TempFile::create_beside(target));
  VXR_RETURN_IF_ERROR(tmp.write(bytes));
  return tmp.commit();
}

Status write_file_atomically(const std::string& target, const std::string& text) {
  return write_file_atomically(target,
                               std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

}  // namespace vxr

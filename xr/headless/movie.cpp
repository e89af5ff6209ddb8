#include "xr/headless/movie.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>  // mkdtemp, getenv
#include <filesystem>
#include <vector>

#include "core/output_file.h"

extern char** environ;

namespace vxr::xr {
namespace fs = std::filesystem;

std::string find_ffmpeg() {
  if (const char* env = std::getenv("VXR_FFMPEG"); env && *env) return ::access(env, X_OK) == 0 ? env : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / "ffmpeg";
    if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return {};
}

Result<std::string> movie_scratch_dir(const std::string& movie) {
  const fs::path out(movie);
  std::string name = ".";  // appended, not "." + string: GCC 12 warns falsely (-Wrestrict) on that
  name += out.filename().string();
  name += ".frames.XXXXXX";
  std::string templ = ((out.has_parent_path() ? out.parent_path() : fs::path(".")) / name).string();
  if (!::mkdtemp(templ.data())) return io_error(movie + ": cannot create a scratch folder for the frames beside it");
  return templ;
}

Status encode_movie(const std::string& png_dir, double fps, const std::string& output) {
  if (!(fps > 0.0 && fps <= 1000.0)) return invalid_argument("--fps: give frames per second in (0, 1000]");
  const std::string ffmpeg = find_ffmpeg();
  if (ffmpeg.empty())
    return unsupported(output + ": writing MP4 needs ffmpeg, which is not installed (apt-get install ffmpeg); "
                                "or write the PNG sequence with --png-dir DIR --png-every-frame");
  std::vector<fs::path> frames;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(png_dir, ec))
    if (e.path().extension() == ".png") frames.push_back(e.path());
  if (frames.empty()) return not_found(png_dir + ": no frames were rendered, so there is no movie to write");
  std::sort(frames.begin(), frames.end());
  // ffmpeg's image sequence input needs consecutive numbers: link them so.
  const fs::path seq = fs::path(png_dir) / "seq";
  fs::create_directories(seq, ec);
  for (size_t i = 0; i < frames.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%08zu.png", i);
    fs::create_hard_link(frames[i], seq / name, ec);
    if (ec) return io_error(png_dir + ": cannot prepare the frame sequence (" + ec.message() + ")");
  }
  VXR_ASSIGN_OR_RETURN(TempFile tmp, TempFile::create_beside(output));
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.9g", fps);
  const std::string pattern = (seq / "%08d.png").string();
  // Even sizes for yuv420p; H.264 in MP4 plays everywhere.
  std::vector<std::string> args = {ffmpeg, "-hide_banner", "-loglevel", "error", "-nostdin", "-y",
                                   "-framerate", rate, "-i", pattern, "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                   "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4", tmp.path()};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, ffmpeg.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
    return io_error(output + ": cannot start " + ffmpeg);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return io_error(output + ": ffmpeg failed to encode the " + std::to_string(frames.size()) +
                    " frames (its message is above); the PNG frames are in " + png_dir);
  return tmp.commit();
}

}  // namespace vxr::xr

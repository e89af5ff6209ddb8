#include "xr/desktop/viewer_movie.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/output_file.h"
#include "xr/headless/movie.h"

namespace vxr::xr {
namespace {

bool is_mp4(const std::string& output) { return std::filesystem::path(output).extension() == ".mp4"; }

std::string frame_name(uint64_t frame) {
  char name[32];
  std::snprintf(name, sizeof name, "frame-%05llu.png", static_cast<unsigned long long>(frame));
  return name;
}

}  // namespace

Status check_movie_output(const MovieRequest& r, std::span<const std::string> inputs) {
  if (r.output.empty()) return invalid_argument("movie: give an output (NAME.mp4 or a folder for PNG frames)");
  if (r.frames < 2) return invalid_argument(r.output + ": a movie needs 2 frames or more");
  if (!(r.fps > 0.0) || !std::isfinite(r.fps)) return invalid_argument(r.output + ": frames per second must be > 0");
  if (is_mp4(r.output)) {
    VXR_RETURN_IF_ERROR(check_output(r.output, inputs, "movie"));
    if (find_ffmpeg().empty())
      return unsupported(r.output + ": writing MP4 needs ffmpeg, which is not installed (apt-get install ffmpeg); "
                                    "or give a folder for the PNG frames");
    return Status::ok();
  }
  std::error_code ec;
  const auto status = std::filesystem::status(r.output, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_directory(status))
    return invalid_argument(r.output + ": the movie's frames go into a folder, and this is a file (or give NAME.mp4)");
  if (std::filesystem::is_directory(status))
    return check_output((std::filesystem::path(r.output) / frame_name(0)).string(), inputs, "movie frame");
  return Status::ok();
}

Result<MovieExport> MovieExport::start(const MovieRequest& request, const std::vector<Pose>& keyframes,
                                       std::span<const std::string> inputs) {
  if (keyframes.size() < 2)
    return invalid_argument(request.output + ": a movie needs 2 keyframes or more (" +
                            std::to_string(keyframes.size()) + " added)");
  VXR_RETURN_IF_ERROR(check_movie_output(request, inputs));
  MovieExport m;
  m.request_ = request;
  m.inputs_.assign(inputs.begin(), inputs.end());
  m.path_.interpolation = Interpolation::kSmooth;
  const double span = double(request.frames - 1) / double(keyframes.size() - 1);
  for (size_t k = 0; k < keyframes.size(); ++k) {
    ScriptFrame f = default_script_frame();
    f.head = keyframes[k];
    const uint64_t at = uint64_t(std::llround(double(k) * span));
    if (!m.path_.keys.empty() && at <= m.path_.keys.back().first)
      return invalid_argument(request.output + ": " + std::to_string(request.frames) + " frames are too few for " +
                              std::to_string(keyframes.size()) + " keyframes");
    m.path_.keys.emplace_back(at, f);
  }
  std::error_code ec;
  if (is_mp4(request.output)) {
    VXR_ASSIGN_OR_RETURN(m.frame_dir_, movie_scratch_dir(request.output));
  } else {
    std::filesystem::create_directories(request.output, ec);
    if (ec) return io_error(request.output + ": cannot create the folder for the frames (" + ec.message() + ")");
    m.frame_dir_ = request.output;
  }
  return m;
}

Pose MovieExport::pose(uint64_t frame) const { return path_.at(double(frame)).head; }

Result<std::string> MovieExport::frame_path(uint64_t frame) const {
  const std::string path = (std::filesystem::path(frame_dir_) / frame_name(frame)).string();
  VXR_RETURN_IF_ERROR(check_output(path, inputs_, "movie frame"));
  return path;
}

Result<std::string> MovieExport::finish() {
  if (!is_mp4(request_.output)) return request_.output;
  const Status encoded = encode_movie(frame_dir_, request_.fps, request_.output);
  if (!encoded) return encoded;  // the frames stay in the scratch folder the message names
  std::error_code ec;
  std::filesystem::remove_all(frame_dir_, ec);
  return request_.output;
}

}  // namespace vxr::xr

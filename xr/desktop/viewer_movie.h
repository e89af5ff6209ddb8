// Movie export from the desktop viewer: keyframes of the window's camera and
// the smooth path through them (xr/script.h: Hermite positions, SQUAD
// rotations, easing in and out at the ends), frame by frame, into a PNG
// sequence or an MP4 (xr/headless/movie.h, ffmpeg). The window renders each
// frame with its own renderer and settings; this file only plans: poses,
// file names, progress. No window system here.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/status.h"
#include "xr/pose.h"
#include "xr/script.h"

namespace vxr::xr {

struct MovieRequest {
  std::string output;   // NAME.mp4 (needs ffmpeg), else a folder of frame-NNNNN.png
  uint64_t frames = 0;  // >= 2
  double fps = 30.0;
};

// Checks an output before anything is rendered: an .mp4 through check_output
// (never an input, a folder or a special file) and ffmpeg on the machine; a
// folder that is not a file, whose frames check_output accepts where it
// exists already. One line naming the output and the problem.
Status check_movie_output(const MovieRequest& request, std::span<const std::string> inputs);

// One export in progress: the path through the keyframes and where frame i goes.
class MovieExport {
 public:
  // Needs 2 keyframes or more (the window's head poses) and 2 frames or more.
  // Creates the output folder (or, for an .mp4, a scratch folder beside it).
  static Result<MovieExport> start(const MovieRequest& request, const std::vector<Pose>& keyframes,
                                   std::span<const std::string> inputs);

  const MovieRequest& request() const { return request_; }
  uint64_t next_frame() const { return next_; }
  bool done() const { return next_ >= request_.frames; }
  double progress() const { return double(next_) / double(request_.frames); }
  // The pose of frame i: keyframe k at frame round(k (frames - 1) / (keys - 1)).
  Pose pose(uint64_t frame) const;
  // Where frame i's PNG goes (checked with check_output against the inputs).
  Result<std::string> frame_path(uint64_t frame) const;
  // Frame next_frame() was written: on to the next.
  void frame_written() { ++next_; }
  // After the last frame: the MP4 encoded from the scratch folder (then
  // removed), or nothing for a PNG sequence. Returns what was written.
  Result<std::string> finish();

 private:
  MovieRequest request_;
  Script path_;
  std::string frame_dir_;  // the output folder, or the scratch folder of an .mp4
  std::vector<std::string> inputs_;
  uint64_t next_ = 0;
};

}  // namespace vxr::xr

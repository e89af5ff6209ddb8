// Camera movies: the headless target writes one PNG per rendered frame into a
// scratch folder (a pose script with "interpolation": "smooth" is the camera
// path), and encode_movie turns the sequence into an H.264 MP4 with ffmpeg
// when it is installed. Without ffmpeg the PNG sequence itself is the movie
// (`vxr view --headless --png-every-frame --png-dir DIR`).
#pragma once

#include <string>

#include "core/status.h"

namespace vxr::xr {

// The ffmpeg executable: $VXR_FFMPEG, else `ffmpeg` on PATH; empty when none.
std::string find_ffmpeg();

// A new scratch folder for the frames of movie `movie`, beside it
// ("<dir>/.<name>.frames.XXXXXX"), so the frames land on the movie's disk.
Result<std::string> movie_scratch_dir(const std::string& movie);

// Encodes every *.png in `png_dir` (sorted by name; gaps in the numbering are
// fine) at `fps` frames per second into `output` (.mp4), through a temp file
// beside it renamed into place when ffmpeg succeeds. Errors name the file and
// what to do (install ffmpeg, or keep the PNG sequence).
Status encode_movie(const std::string& png_dir, double fps, const std::string& output);

}  // namespace vxr::xr

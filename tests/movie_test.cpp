// Camera movies: `vxr view --headless --script PATH --movie out.mp4` renders
// the pose script's (smooth) camera path through the same renderer and
// encodes it with ffmpeg; without ffmpeg it says so and leaves nothing behind.
#include <doctest/doctest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.h"
#include "xr/headless/movie.h"

using vxr::test::CliRun;
using vxr::test::run_vxr;
namespace fs = std::filesystem;

namespace {

std::string q(const fs::path& p) { return vxr::test::shell_quote(p.string()); }

fs::path write_camera_path(const fs::path& dir) {
  const fs::path p = dir / "path.json";
  std::ofstream(p) << R"({"interpolation": "smooth", "view": {"width": 64, "height": 48},
    "keys": [{"frame": 0,  "head": {"position": [0, 1.6, 0.3],  "orientation": [0, 0, 0, 1]}},
             {"frame": 8,  "head": {"position": [0.2, 1.6, 0.1], "orientation": [0, 0.1305262, 0, 0.9914449]}},
             {"frame": 15, "head": {"position": [0.3, 1.7, -0.1], "orientation": [0, 0.258819, 0, 0.9659258]}}]})";
  return p;
}

bool leftovers(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (n.find(".partial") != std::string::npos || n.find(".frames.") != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("movie: a smooth camera path becomes an MP4 when ffmpeg is there, a clear error when not") {
  const fs::path dir = vxr::test::scratch_dir("movie", "camera_path");
  const fs::path script = write_camera_path(dir);
  const std::string args = "view procedural:vessels:256 --headless --script " + q(script) + " --fps 12 --movie ";

  // Without ffmpeg: one line naming the file and what to do, exit 1, nothing left behind.
  ::setenv("VXR_FFMPEG", "/nonexistent/ffmpeg", 1);
  const CliRun none = run_vxr(args + q(dir / "a.mp4"), dir, 300);
  ::unsetenv("VXR_FFMPEG");
  CHECK(none.rc == 1);
  CHECK(none.err.find("a.mp4: writing MP4 needs ffmpeg, which is not installed") != std::string::npos);
  CHECK(!fs::exists(dir / "a.mp4"));
  CHECK(!leftovers(dir));

  if (vxr::xr::find_ffmpeg().empty()) {
    MESSAGE("ffmpeg is not installed here: the MP4 encode itself is not exercised");
  } else {
    const CliRun ok = run_vxr(args + q(dir / "b.mp4"), dir, 300);
    REQUIRE_MESSAGE(ok.rc == 0, ok.err);
    CHECK(ok.out.find("movie " + (dir / "b.mp4").string() + ": 16 frames at 12 fps") != std::string::npos);
    std::ifstream f(dir / "b.mp4", std::ios::binary);
    char head[8] = {};
    f.read(head, 8);
    CHECK(std::string(head + 4, 4) == "ftyp");
    CHECK(!leftovers(dir));
  }

  CHECK(run_vxr(args + q(dir / "c.png"), dir).rc == 2);
  CHECK(run_vxr("view --desktop --movie " + q(dir / "d.mp4"), dir).rc == 2);
  CHECK(run_vxr(args + q(script), dir).rc == 2);  // the script is an input
}

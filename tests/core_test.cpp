#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/image.h"
#include "core/progress.h"
#include "core/status.h"
#include "volume/dense_volume.h"

using namespace vxr;

namespace {
Result<int> parse_positive(int v) {
  if (v <= 0) return invalid_argument("not positive: " + std::to_string(v));
  return v;
}
Status doubled_positive(int v, int* out) {
  VXR_ASSIGN_OR_RETURN(int x, parse_positive(v));
  *out = 2 * x;
  return Status::ok();
}
}  // namespace

TEST_CASE("core: Result carries a value or the Status that explains its absence") {
  int out = 0;
  CHECK(doubled_positive(21, &out).is_ok());
  CHECK(out == 42);
  Status s = doubled_positive(-1, &out);
  CHECK(s.code() == ErrorCode::kInvalidArgument);
  CHECK(s.to_string() == "invalid argument: not positive: -1");
}

TEST_CASE("core: PNG write then read returns the same pixels, and no partial file is left") {
  ImageRgba8 img(7, 5);
  for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = static_cast<uint8_t>(i * 37 + 11);
  const std::string path = (std::filesystem::temp_directory_path() / "vxr_core_png_test.png").string();
  REQUIRE(write_png(path, img).is_ok());
  CHECK_FALSE(std::filesystem::exists(path + ".partial"));
  auto back = read_png(path);
  REQUIRE(back.is_ok());
  CHECK(back->width == 7);
  CHECK(back->height == 5);
  CHECK(back->pixels == img.pixels);
  std::remove(path.c_str());
}

TEST_CASE("core: reading a non-PNG names the file and the problem") {
  const std::string path = (std::filesystem::temp_directory_path() / "vxr_not_a.png").string();
  std::ofstream(path) << "hello, not a png";
  auto r = read_png(path);
  CHECK_FALSE(r.is_ok());
  CHECK(r.status().code() == ErrorCode::kCorrupt);
  CHECK(r.status().message().find(path) != std::string::npos);
  std::remove(path.c_str());
}

TEST_CASE("core: writing a PNG into a missing folder fails cleanly") {
  ImageRgba8 img(2, 2);
  Status s = write_png("/nonexistent-dir/x.png", img);
  CHECK(s.code() == ErrorCode::kIo);
  CHECK(s.message().find("/nonexistent-dir/x.png") != std::string::npos);
}

TEST_CASE("core: progress line shows percent, rate and ETA") {
  Progress p("import", 1000);
  p.advance(250);
  const std::string line = p.status_line();
  CHECK(line.find("25.0%") != std::string::npos);
  CHECK(line.find("MB/s") != std::string::npos);
  CHECK(line.find("ETA") != std::string::npos);
}

TEST_CASE("volume: raw volume sidecar is checked against the file size") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "vxr_raw_test";
  fs::create_directories(dir);
  std::ofstream(dir / "v.raw", std::ios::binary).write("\x01\x02\x03\x04\x05\x06\x07\x08", 8);
  std::ofstream(dir / "good.json") << R"({"file":"v.raw","dims":[2,2,2],"dtype":"u8","voxel_size":[1,1,2]})";
  std::ofstream(dir / "bad.json") << R"({"file":"v.raw","dims":[2,2,3],"dtype":"u8"})";
  auto good = load_raw_volume((dir / "good.json").string());
  REQUIRE(good.is_ok());
  CHECK(good->value_at(1, 1, 1) == 8);
  CHECK(good->voxel_size[2] == 2.0);
  auto bad = load_raw_volume((dir / "bad.json").string());
  CHECK(bad.status().code() == ErrorCode::kCorrupt);
  fs::remove_all(dir);
}

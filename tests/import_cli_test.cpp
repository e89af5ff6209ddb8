// `vxr import` / `vxr info` / `vxr export-tiff` as a user runs them, on every
// file in ../shared/testdata/{tiff,ome-tiff,imaris,slices} and on broken copies.
#include <doctest/doctest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_runner.h"
#include "volume/importers/import_source.h"

using namespace vxr;
namespace fs = std::filesystem;

namespace {

const std::string kData = VXR_TESTDATA_DIR;

using Run = vxr::test::CliRun;

fs::path scratch(const std::string& name) { return vxr::test::scratch_dir("import_cli", name); }

std::string quote(const std::string& s) { return vxr::test::shell_quote(s); }

Run run_vxr(const std::string& args, const fs::path& dir) { return vxr::test::run_vxr(args, dir); }

struct Expect {
  const char* input;  // relative to testdata
  uint64_t x, y, z;
  const char* dtype;
  uint32_t channels, timepoints;
  double vx, vy, vz;
  const char* unit;
};

// SOURCES.md's figures; a picture is one slice with one channel per sample.
const Expect kAll[] = {
    {"tiff/shapes_uncompressed.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_deflate.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_tiled.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_planar.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_tiled_planar.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_uncompressed_tiled_planar.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_12bps.tif", 128, 72, 1, "u16", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_14bps.tif", 128, 72, 1, "u16", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_planar_10bps.tif", 128, 72, 1, "u16", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_predictor3.tif", 128, 72, 1, "f32", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_lzw_palette.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_multi_size.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_multi_color.tif", 128, 72, 3, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_hyper.tif", 128, 72, 1, "f32", 7, 1, 1, 1, 1, "px"},
    {"tiff/shapes_tiled_multi.tif", 128, 72, 3, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_zstd.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/shapes_jpg.tif", 128, 72, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/mri-stack-calibrated.tif", 186, 226, 27, "u8", 1, 1, 1, 1, 5, "um"},
    {"tiff/hopper_bigtiff.tif", 128, 128, 1, "u8", 3, 1, 1, 1, 1, "px"},
    {"tiff/tiff_tiled_planar_lzw.tiff", 278, 374, 1, "u8", 3, 1, 352.777, 352.777, 1, "um"},
    {"tiff/tiff_strip_planar_16bit_RGBa.tiff", 100, 40, 1, "u16", 4, 1, 1, 1, 1, "px"},
    {"ome-tiff/z-series.ome.tif", 439, 167, 5, "i8", 1, 1, 1, 1, 1, "px"},
    {"ome-tiff/multi-channel-z-series.ome.tif", 439, 167, 5, "i8", 3, 1, 1, 1, 1, "px"},
    {"ome-tiff/multi-channel-time-series.ome.tif", 439, 167, 1, "i8", 3, 7, 1, 1, 1, "px"},
    {"ome-tiff/multifile-master/multifile-Z1.ome.tiff", 18, 24, 5, "u8", 1, 1, 1, 1, 1, "px"},
    {"ome-tiff/multifile-master/multifile-Z4.ome.tiff", 18, 24, 5, "u8", 1, 1, 1, 1, 1, "px"},
    {"ome-tiff/multifile-companion/multifile.companion.ome", 18, 24, 5, "u8", 1, 1, 1, 1, 1, "px"},
    {"ome-tiff/multifile-companion/multifile-Z2.ome.tiff", 18, 24, 5, "u8", 1, 1, 1, 1, 1, "px"},
    {"imaris/Minimal_IMS_File.ims", 128, 128, 1, "u16", 1, 1, 7.0 / 128, 7.0 / 128, 0.1, "um"},
    {"slices/mri-stack", 186, 226, 27, "u8", 1, 1, 1, 1, 1, "px"},
};

}  // namespace

TEST_CASE("cli import: every testdata file imports and vxr info --json reports its dims, dtype, channels, timepoints, voxel size") {
  const fs::path dir = scratch("all");
  int i = 0;
  for (const Expect& e : kAll) {
    CAPTURE(e.input);
    char name[32];
    std::snprintf(name, sizeof name, "f%d.vxc", i++);
    const fs::path out = dir / name;
    const Run imp = run_vxr("import " + quote(kData + "/" + e.input) + " -o " + quote(out.string()) + " --chunk 32", dir);
    REQUIRE_MESSAGE(imp.rc == 0, imp.err);
    const Run info = run_vxr("info --json " + quote(out.string()), dir);
    REQUIRE_MESSAGE(info.rc == 0, info.err);
    const nlohmann::json j = nlohmann::json::parse(info.out, nullptr, false);
    REQUIRE_FALSE(j.is_discarded());
    CHECK(j["dims"] == nlohmann::json({e.x, e.y, e.z}));
    CHECK(j["dtype"] == e.dtype);
    CHECK(j["channels"] == e.channels);
    CHECK(j["timepoints"] == e.timepoints);
    CHECK(j["voxel_size"][0].get<double>() == doctest::Approx(e.vx).epsilon(0.001));
    CHECK(j["voxel_size"][1].get<double>() == doctest::Approx(e.vy).epsilon(0.001));
    CHECK(j["voxel_size"][2].get<double>() == doctest::Approx(e.vz).epsilon(0.001));
    CHECK(j["unit"] == e.unit);
  }
}

TEST_CASE("cli info: an importable file is described as it is, without importing, with the figures import gives") {
  const fs::path dir = scratch("info_importable");
  for (const Expect& e : kAll) {
    CAPTURE(e.input);
    const Run info = run_vxr("info --json " + quote(kData + "/" + e.input), dir);
    REQUIRE_MESSAGE(info.rc == 0, info.err);
    const nlohmann::json j = nlohmann::json::parse(info.out, nullptr, false);
    REQUIRE_FALSE(j.is_discarded());
    CHECK(j["container"] == false);
    CHECK_FALSE(j["format"].get<std::string>().empty());
    CHECK(j["dims"] == nlohmann::json({e.x, e.y, e.z}));
    CHECK(j["dtype"] == e.dtype);
    CHECK(j["channels"] == e.channels);
    CHECK(j["timepoints"] == e.timepoints);
    CHECK(j["voxel_size"][2].get<double>() == doctest::Approx(e.vz).epsilon(0.001));
    CHECK(j["unit"] == e.unit);
  }
  for (const auto& f : fs::directory_iterator(dir)) CHECK(f.path().filename() == "stderr.txt");  // nothing written

  // A container under another name is still read as a container; a file that is neither fails naming it.
  const fs::path vxc = dir / "mri.vxc", renamed = dir / "mri.data";
  REQUIRE(run_vxr("import " + quote(kData + "/slices/mri-stack") + " -o " + quote(vxc.string()) + " --chunk 32", dir).rc == 0);
  fs::copy_file(vxc, renamed);
  const Run as_container = run_vxr("info --json " + quote(renamed.string()), dir);
  REQUIRE_MESSAGE(as_container.rc == 0, as_container.err);
  const nlohmann::json j = nlohmann::json::parse(as_container.out, nullptr, false);
  CHECK(j.contains("chunks"));
  CHECK(j["dims"] == nlohmann::json({186, 226, 27}));
  std::ofstream(dir / "notes.txt") << "not an image\n";
  const Run bad = run_vxr("info " + quote((dir / "notes.txt").string()), dir);
  CHECK(bad.rc != 0);
  CHECK(bad.err.find("notes.txt") != std::string::npos);
  CHECK(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);
}

TEST_CASE("cli import: bad input exits non-zero with one line naming the file, and leaves nothing vxr info accepts") {
  const fs::path dir = scratch("bad");
  const fs::path in = dir / "inputs";
  fs::create_directories(in);
  // Truncated TIFF.
  fs::copy_file(kData + "/slices/mri-stack/mri-stack-0000.tif", in / "truncated.tif");
  fs::resize_file(in / "truncated.tif", fs::file_size(in / "truncated.tif") / 2);
  // Absurd dimensions: ImageWidth/ImageLength/RowsPerStrip patched to 2^32-16 (classic big-endian IFD at 8).
  {
    fs::copy_file(kData + "/slices/mri-stack/mri-stack-0000.tif", in / "absurd.tif");
    std::fstream f(in / "absurd.tif", std::ios::in | std::ios::out | std::ios::binary);
    std::vector<uint8_t> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    REQUIRE(b[0] == 'M');
    const uint32_t ifd = uint32_t(b[4]) << 24 | uint32_t(b[5]) << 16 | uint32_t(b[6]) << 8 | b[7];
    const uint16_t n = uint16_t(b[ifd] << 8 | b[ifd + 1]);
    for (uint16_t k = 0; k < n; ++k) {
      const size_t e = ifd + 2 + 12 * size_t(k);
      const uint16_t tag = uint16_t(b[e] << 8 | b[e + 1]);
      if (tag != 256 && tag != 257 && tag != 278) continue;
      const uint8_t v[10] = {0, 4, 0, 0, 0, 1, 0xFF, 0xFF, 0xFF, 0xF0};
      std::copy(v, v + 10, b.begin() + long(e) + 2);
    }
    f.seekp(0);
    f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
  }
  std::ofstream(in / "fake.tif") << "not a tiff at all\n";
  fs::create_directories(in / "empty");
  fs::create_directories(in / "mixed");
  for (const char* s : {"mri-stack-0000.tif", "mri-stack-0001.tif", "mri-stack-0003.tif"})
    fs::copy_file(kData + "/slices/mri-stack/" + s, in / "mixed" / s);
  fs::copy_file(kData + "/tiff/shapes_uncompressed.tif", in / "mixed" / "mri-stack-0002.tif");
  // .ims without DataSet.
  {
    fs::copy_file(kData + "/imaris/Minimal_IMS_File.ims", in / "nodataset.ims");
    const hid_t h = H5Fopen((in / "nodataset.ims").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(h >= 0);
    REQUIRE(H5Ldelete(h, "DataSet", H5P_DEFAULT) >= 0);
    H5Fclose(h);
  }
  const std::pair<const char*, const char*> kBad[] = {
      {"truncated.tif", "truncated"},          {"absurd.tif", "absurd dimensions"},
      {"fake.tif", "not a TIFF file"},         {"empty", "folder holds no"},
      {"mixed", "mri-stack-0002.tif: is 128x72"}, {"nodataset.ims", "no DataSet group"},
  };
  for (auto [name, problem] : kBad) {
    CAPTURE(name);
    const fs::path out = dir / (std::string(name) + ".vxc");
    const Run r = run_vxr("import " + quote((in / name).string()) + " -o " + quote(out.string()), dir);
    CHECK(r.rc == 1);
    CHECK_MESSAGE(r.err.find((in / name).string()) != std::string::npos, r.err);
    CHECK_MESSAGE(r.err.find(problem) != std::string::npos, r.err);
    CHECK_MESSAGE(std::count(r.err.begin(), r.err.end(), '\n') == 1, r.err);
    CHECK(run_vxr("info " + quote(out.string()), dir).rc != 0);
    CHECK(run_vxr("info " + quote(out.string() + ".partial"), dir).rc != 0);
  }
}

TEST_CASE("cli export-tiff: level 0 of imported real files round-trips bit for bit") {
  const fs::path dir = scratch("export");
  for (const char* f : {"tiff/mri-stack-calibrated.tif", "ome-tiff/multi-channel-time-series.ome.tif",
                        "tiff/tiff_strip_planar_16bit_RGBa.tiff", "tiff/shapes_lzw_predictor3.tif",
                        "imaris/Minimal_IMS_File.ims"}) {
    CAPTURE(f);
    const fs::path vxc = dir / "x.vxc", tif = dir / "x.tif";
    fs::remove(vxc), fs::remove(tif);
    REQUIRE(run_vxr("import " + quote(kData + "/" + f) + " -o " + quote(vxc.string()) + " --chunk 32", dir).rc == 0);
    const Run ex = run_vxr("export-tiff " + quote(vxc.string()) + " -o " + quote(tif.string()), dir);
    REQUIRE_MESSAGE(ex.rc == 0, ex.err);
    auto a = open_import_source({kData + "/" + f});
    auto b = open_import_source({tif.string()});
    REQUIRE(a.is_ok());
    REQUIRE_MESSAGE(b.is_ok(), b.status().message());
    const VolumeInfo& ia = (*a)->info();
    const VolumeInfo& ib = (*b)->info();
    CHECK(ib.dims == ia.dims);
    CHECK(ib.dtype == ia.dtype);
    CHECK(ib.channels == ia.channels);
    CHECK(ib.timepoints == ia.timepoints);
    CHECK(ib.unit == ia.unit);
    for (int k = 0; k < 3; ++k) CHECK(ib.voxel_size[k] == doctest::Approx(ia.voxel_size[k]).epsilon(1e-6));
    Box3 box;
    box.size = ia.dims;
    std::vector<uint8_t> va(box.voxels() * dtype_bytes(ia.dtype)), vb(va.size());
    for (uint32_t t = 0; t < ia.timepoints; ++t)
      for (uint32_t c = 0; c < ia.channels; ++c) {
        REQUIRE((*a)->read_region(c, t, box, va).is_ok());
        REQUIRE((*b)->read_region(c, t, box, vb).is_ok());
        CHECK(va == vb);
      }
  }
  // One channel and timepoint, a coarser level, and usage errors.
  const fs::path vxc = dir / "mct.vxc";
  REQUIRE(run_vxr("import " + quote(kData + "/ome-tiff/multi-channel-time-series.ome.tif") + " -o " + quote(vxc.string()),
              dir).rc == 0);
  const Run one = run_vxr("export-tiff " + quote(vxc.string()) + " --channel 2 --timepoint 6 --level 1 -o " +
                          quote((dir / "one.tif").string()), dir);
  REQUIRE_MESSAGE(one.rc == 0, one.err);
  auto o = open_import_source({(dir / "one.tif").string()});
  REQUIRE(o.is_ok());
  CHECK((*o)->info().channels == 1);
  CHECK((*o)->info().timepoints == 1);
  CHECK((*o)->info().dims[0] < 439);
  const Run bad = run_vxr("export-tiff " + quote(vxc.string()) + " --channel 3 -o " + quote((dir / "bad.tif").string()), dir);
  CHECK(bad.rc == 2);
  CHECK_MESSAGE(bad.err.find("--channel 3") != std::string::npos, bad.err);
  CHECK_FALSE(fs::exists(dir / "bad.tif"));
}

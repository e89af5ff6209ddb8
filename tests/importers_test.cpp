// Importers against the real files in ../shared/testdata (expected values from
// SOURCES.md there) and against broken copies of them made in a temp folder.
#include <doctest/doctest.h>
#include <hdf5.h>
#include <tiffio.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "core/image.h"
#include "volume/importers/imagej_metadata.h"
#include "volume/importers/import_source.h"
#include "volume/importers/slice_series_importer.h"
#include "volume/importers/tiff_reader.h"
#include "volume/importers/units.h"

// jpeglib.h needs FILE and size_t declared first.
#include <jpeglib.h>

using namespace vxr;
namespace fs = std::filesystem;

namespace {

const std::string kData = VXR_TESTDATA_DIR;

std::unique_ptr<SlabSource> open_ok(const std::vector<std::string>& inputs) {
  auto r = open_import_source(inputs);
  INFO(inputs[0]);
  REQUIRE_MESSAGE(r.is_ok(), r.status().message());
  return std::move(r).value();
}
std::unique_ptr<SlabSource> open_ok(const std::string& path) { return open_ok(std::vector<std::string>{path}); }

std::vector<uint8_t> read_box(SlabSource& s, uint32_t c, uint32_t t, const Box3& box) {
  std::vector<uint8_t> buf(box.voxels() * dtype_bytes(s.info().dtype));
  const Status st = s.read_region(c, t, box, buf);
  REQUIRE_MESSAGE(st.is_ok(), st.message());
  return buf;
}
std::vector<uint8_t> read_all(SlabSource& s, uint32_t c, uint32_t t = 0) {
  Box3 b;
  b.size = s.info().dims;
  return read_box(s, c, t, b);
}

// A fresh, empty folder for one test's files.
fs::path scratch(const std::string& name) {
  const fs::path p = fs::path(VXR_TEST_OUT_DIR) / "importers" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

std::string error_of(const std::vector<std::string>& inputs) {
  auto r = open_import_source(inputs);
  if (r.is_ok()) return "(opened without error)";
  return r.status().message();
}

struct Expect {
  const char* file;
  uint64_t x, y, z;
  DType dtype;
  uint32_t channels, timepoints;
  double vx, vy, vz;
  const char* unit;
};

void check_info(const Expect& e) {
  CAPTURE(e.file);
  auto s = open_ok(kData + "/" + e.file);
  const VolumeInfo& i = s->info();
  CHECK(i.dims[0] == e.x);
  CHECK(i.dims[1] == e.y);
  CHECK(i.dims[2] == e.z);
  CHECK(dtype_name(i.dtype) == std::string(dtype_name(e.dtype)));
  CHECK(i.channels == e.channels);
  CHECK(i.timepoints == e.timepoints);
  CHECK(i.voxel_size[0] == doctest::Approx(e.vx));
  CHECK(i.voxel_size[1] == doctest::Approx(e.vy));
  CHECK(i.voxel_size[2] == doctest::Approx(e.vz));
  CHECK(i.unit == e.unit);
  // Every channel and timepoint reads.
  for (uint32_t t = 0; t < i.timepoints; ++t)
    for (uint32_t c = 0; c < i.channels; ++c) CHECK(read_all(*s, c, t).size() == i.voxels_per_volume() * dtype_bytes(i.dtype));
}

// Channel c of a shapes_* picture as 8-bit values, whatever the file's type.
std::vector<double> shapes_channel(const std::string& file, uint32_t c, uint32_t z = 0) {
  auto s = open_ok(kData + "/tiff/" + file);
  Box3 b;
  b.origin = {0, 0, z};
  b.size = {s->info().dims[0], s->info().dims[1], 1};
  const auto raw = read_box(*s, c, 0, b);
  std::vector<double> v(b.voxels());
  for (size_t i = 0; i < v.size(); ++i) {
    switch (s->info().dtype) {
      case DType::kU8: v[i] = raw[i]; break;
      case DType::kU16: {
        uint16_t x;
        std::memcpy(&x, &raw[2 * i], 2);
        v[i] = x;
        break;
      }
      case DType::kF32: {
        float f;
        std::memcpy(&f, &raw[4 * i], 4);
        v[i] = f;
        break;
      }
      default: FAIL("unexpected type");
    }
  }
  return v;
}

// Patches one IFD0 entry of a classic TIFF to a LONG value.
void patch_tag(const fs::path& p, uint16_t tag, uint32_t value) {
  std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
  std::vector<uint8_t> b((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const bool be = b[0] == 'M';
  auto rd16 = [&](size_t o) { return be ? uint16_t(b[o] << 8 | b[o + 1]) : uint16_t(b[o + 1] << 8 | b[o]); };
  auto rd32 = [&](size_t o) {
    return be ? uint32_t(b[o]) << 24 | uint32_t(b[o + 1]) << 16 | uint32_t(b[o + 2]) << 8 | b[o + 3]
              : uint32_t(b[o + 3]) << 24 | uint32_t(b[o + 2]) << 16 | uint32_t(b[o + 1]) << 8 | b[o];
  };
  auto wr16 = [&](size_t o, uint16_t v) {
    b[o + (be ? 0 : 1)] = uint8_t(v >> 8), b[o + (be ? 1 : 0)] = uint8_t(v);
  };
  auto wr32 = [&](size_t o, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[o + (be ? i : 3 - i)] = uint8_t(v >> (24 - 8 * i));
  };
  const uint32_t ifd = rd32(4);
  const uint16_t n = rd16(ifd);
  bool found = false;
  for (uint16_t i = 0; i < n; ++i) {
    const size_t e = ifd + 2 + 12 * size_t(i);
    if (rd16(e) != tag) continue;
    wr16(e + 2, 4);  // LONG
    wr32(e + 4, 1);
    wr32(e + 8, value);
    found = true;
  }
  REQUIRE(found);
  f.seekp(0);
  f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

void write_gray_jpeg(const fs::path& p, uint32_t w, uint32_t h, uint8_t value) {
  FILE* f = std::fopen(p.c_str(), "wb");
  REQUIRE(f);
  jpeg_compress_struct c;
  jpeg_error_mgr err;
  c.err = jpeg_std_error(&err);
  jpeg_create_compress(&c);
  jpeg_stdio_dest(&c, f);
  c.image_width = w;
  c.image_height = h;
  c.input_components = 1;
  c.in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, 100, TRUE);
  jpeg_start_compress(&c, TRUE);
  std::vector<uint8_t> row(w, value);
  while (c.next_scanline < h) {
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&c, &r, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  std::fclose(f);
}

}  // namespace

TEST_CASE("importers: every TIFF in testdata/tiff opens with the dims, type, channels and voxel size SOURCES.md gives") {
  // A 2D or RGB picture is a one-slice volume with one channel per sample.
  const Expect kTiff[] = {
      {"tiff/shapes_uncompressed.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_deflate.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_tiled.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_planar.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_tiled_planar.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_uncompressed_tiled_planar.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_12bps.tif", 128, 72, 1, DType::kU16, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_14bps.tif", 128, 72, 1, DType::kU16, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_planar_10bps.tif", 128, 72, 1, DType::kU16, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_predictor3.tif", 128, 72, 1, DType::kF32, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_lzw_palette.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},  // palette -> RGB
      {"tiff/shapes_multi_size.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},   // first series only
      {"tiff/shapes_multi_color.tif", 128, 72, 3, DType::kU8, 3, 1, 1, 1, 1, "px"},  // pages 0-2 (page 3 is 12-bit)
      {"tiff/shapes_hyper.tif", 128, 72, 1, DType::kF32, 7, 1, 1, 1, 1, "px"},
      {"tiff/shapes_tiled_multi.tif", 128, 72, 3, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_zstd.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/shapes_jpg.tif", 128, 72, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      {"tiff/mri-stack-calibrated.tif", 186, 226, 27, DType::kU8, 1, 1, 1, 1, 5, "um"},
      {"tiff/hopper_bigtiff.tif", 128, 128, 1, DType::kU8, 3, 1, 1, 1, 1, "px"},
      // ResolutionUnit=cm, 28.3465 px/cm (72 dpi) -> 352.8 um pixels, no z spacing.
      {"tiff/tiff_tiled_planar_lzw.tiff", 278, 374, 1, DType::kU8, 3, 1, 352.8, 352.8, 1, "um"},
      {"tiff/tiff_strip_planar_16bit_RGBa.tiff", 100, 40, 1, DType::kU16, 4, 1, 1, 1, 1, "px"},
  };
  for (const Expect& e : kTiff) {
    if (std::string(e.file) == "tiff/tiff_tiled_planar_lzw.tiff") {
      auto s = open_ok(kData + "/" + e.file);
      CHECK(s->info().voxel_size[0] == doctest::Approx(352.8).epsilon(0.01));
      CHECK(s->info().dims[0] == 278);
      CHECK(s->info().channels == 3);
      continue;
    }
    check_info(e);
  }
  size_t n = 0;
  for (const auto& f : fs::directory_iterator(kData + "/tiff")) n += f.is_regular_file();
  CHECK(n == std::size(kTiff));
}

TEST_CASE("importers: pages that differ in size import the first series and say so") {
  auto s = open_ok(kData + "/tiff/shapes_multi_size.tif");
  REQUIRE(s->warnings().size() == 1);
  const std::string w = s->warnings()[0];
  CHECK(w.find("shapes_multi_size.tif") != std::string::npos);
  CHECK(w.find("first series (128x72") != std::string::npos);
  CHECK(w.find("skipped 1 page") != std::string::npos);
  CHECK(w.find("64x36") != std::string::npos);
  // A uniform stack has nothing to say.
  CHECK(open_ok(kData + "/tiff/shapes_tiled_multi.tif")->warnings().empty());
}

TEST_CASE("importers: every shapes_* encoding decodes to the same picture") {
  // Reference: uncompressed, big-endian, strips, chunky.
  std::vector<std::vector<double>> ref;
  for (uint32_t c = 0; c < 3; ++c) ref.push_back(shapes_channel("shapes_uncompressed.tif", c));
  // Lossless 8-bit variants: bit for bit.
  for (const char* f : {"shapes_deflate.tif", "shapes_lzw.tif", "shapes_lzw_tiled.tif", "shapes_lzw_planar.tif",
                        "shapes_lzw_tiled_planar.tif", "shapes_uncompressed_tiled_planar.tif", "shapes_zstd.tif",
                        "shapes_multi_size.tif", "shapes_multi_color.tif", "shapes_tiled_multi.tif"}) {
    CAPTURE(f);
    for (uint32_t c = 0; c < 3; ++c) CHECK(shapes_channel(f, c) == ref[c]);
  }
  // Every page of the tiled stack, and the palette page of multi_color, too.
  for (uint32_t z = 1; z < 3; ++z) {
    CAPTURE(z);
    for (uint32_t c = 0; c < 3; ++c) {
      CHECK(shapes_channel("shapes_tiled_multi.tif", c, z) == ref[c]);
      if (z == 2) CHECK(shapes_channel("shapes_multi_color.tif", c, z) == ref[c]);
    }
  }
  // Palette pages (shapes_lzw_palette, page 1 of shapes_multi_color) come out as RGB: the picture
  // quantised to 256 colours.
  for (auto [f, z] : {std::pair{"shapes_lzw_palette.tif", 0u}, std::pair{"shapes_multi_color.tif", 1u}}) {
    CAPTURE(f);
    for (uint32_t c = 0; c < 3; ++c) {
      const auto v = shapes_channel(f, c, z);
      double sum = 0, worst = 0;
      size_t same = 0;
      for (size_t i = 0; i < v.size(); ++i) {
        sum += std::abs(v[i] - ref[c][i]);
        worst = std::max(worst, std::abs(v[i] - ref[c][i]));
        same += v[i] == ref[c][i];
      }
      // Measured: mean |diff| 3.6-4.9, 65-78 % of pixels exact (dithered 256-colour quantisation; the
      // colour map holds 16-bit means such as 0xFFB3). A wrong channel or index mapping is far off both.
      CHECK(sum / double(v.size()) < 6.0);
      CHECK(double(same) / double(v.size()) > 0.6);
      CHECK(worst <= 255);
    }
  }
  // Packed 10/12/14-bit: the same picture scaled to the wider range.
  for (auto [f, max] : {std::pair{"shapes_lzw_12bps.tif", 4095.0}, std::pair{"shapes_lzw_14bps.tif", 16383.0},
                        std::pair{"shapes_lzw_planar_10bps.tif", 1023.0}}) {
    CAPTURE(f);
    for (uint32_t c = 0; c < 3; ++c) {
      const auto v = shapes_channel(f, c);
      size_t bad = 0;
      for (size_t i = 0; i < v.size(); ++i) bad += std::abs(v[i] / max * 255.0 - ref[c][i]) > 0.51;
      CHECK(bad == 0);
    }
  }
  // Float with predictor 3, and the first 3 of shapes_hyper's 7 float channels: value/255.
  for (const char* f : {"shapes_lzw_predictor3.tif", "shapes_hyper.tif"}) {
    CAPTURE(f);
    for (uint32_t c = 0; c < 3; ++c) {
      const auto v = shapes_channel(f, c);
      size_t bad = 0;
      for (size_t i = 0; i < v.size(); ++i) bad += std::abs(v[i] * 255.0 - ref[c][i]) > 0.51;
      CHECK(bad == 0);
    }
  }
  // JPEG is lossy: close on average.
  for (uint32_t c = 0; c < 3; ++c) {
    const auto v = shapes_channel("shapes_jpg.tif", c);
    double sum = 0;
    for (size_t i = 0; i < v.size(); ++i) sum += std::abs(v[i] - ref[c][i]);
    CHECK(sum / double(v.size()) < 4.0);
  }
}

TEST_CASE("importers: sub-box reads equal the same part of a whole read") {
  // Strips, tiles with partial edge tiles, planar, packed bits, palette, BigTIFF, multi-file OME, Imaris.
  for (const char* f : {"tiff/shapes_lzw.tif", "tiff/shapes_lzw_tiled_planar.tif", "tiff/tiff_tiled_planar_lzw.tiff",
                        "tiff/shapes_lzw_12bps.tif", "tiff/shapes_lzw_palette.tif", "tiff/hopper_bigtiff.tif",
                        "tiff/mri-stack-calibrated.tif", "ome-tiff/multifile-master/multifile-Z3.ome.tiff",
                        "ome-tiff/multi-channel-time-series.ome.tif", "imaris/Minimal_IMS_File.ims", "slices/mri-stack"}) {
    CAPTURE(f);
    auto s = open_ok(kData + "/" + f);
    const VolumeInfo& i = s->info();
    const uint32_t c = i.channels - 1, t = i.timepoints - 1, ob = dtype_bytes(i.dtype);
    const auto all = read_all(*s, c, t);
    Box3 b;
    b.origin = {i.dims[0] / 3, i.dims[1] / 4, i.dims[2] / 2};
    b.size = {std::max<uint64_t>(1, i.dims[0] / 2), std::max<uint64_t>(1, i.dims[1] / 2),
              std::max<uint64_t>(1, (i.dims[2] + 1) / 3)};
    const auto part = read_box(*s, c, t, b);
    size_t bad = 0;
    for (uint64_t z = 0; z < b.size[2]; ++z)
      for (uint64_t y = 0; y < b.size[1]; ++y)
        bad += std::memcmp(&part[((z * b.size[1] + y) * b.size[0]) * ob],
                           &all[(((b.origin[2] + z) * i.dims[1] + b.origin[1] + y) * i.dims[0] + b.origin[0]) * ob],
                           b.size[0] * ob) != 0;
    CHECK(bad == 0);
  }
}

TEST_CASE("importers: ImageJ stack mri-stack-calibrated equals the slice folder thresholded above 74") {
  auto stack = open_ok(kData + "/tiff/mri-stack-calibrated.tif");
  auto slices = open_ok(kData + "/slices/mri-stack");
  CHECK(slices->info().dims == std::array<uint64_t, 3>{186, 226, 27});
  CHECK(slices->info().dtype == DType::kU8);
  CHECK(slices->info().channels == 1);
  const auto a = read_all(*stack, 0), b = read_all(*slices, 0);
  REQUIRE(a.size() == b.size());
  size_t bad = 0, fg = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    bad += a[i] != (b[i] > 74 ? 255 : 0);
    fg += a[i] == 255;
  }
  CHECK(bad == 0);
  CHECK(double(fg) / double(a.size()) == doctest::Approx(0.092).epsilon(0.05));  // SOURCES.md: ~9.2 % foreground
}

TEST_CASE("importers: OME-TIFF sizes, signed int8, DimensionOrder and multi-file TiffData mapping") {
  const Expect kOme[] = {
      {"ome-tiff/z-series.ome.tif", 439, 167, 5, DType::kI8, 1, 1, 1, 1, 1, "px"},
      {"ome-tiff/multi-channel-z-series.ome.tif", 439, 167, 5, DType::kI8, 3, 1, 1, 1, 1, "px"},
      {"ome-tiff/multi-channel-time-series.ome.tif", 439, 167, 1, DType::kI8, 3, 7, 1, 1, 1, "px"},
  };
  for (const Expect& e : kOme) check_info(e);
  // Every file of both multi-file sets (and the companion) opens the whole 5-plane dataset.
  std::vector<std::vector<uint8_t>> planes;
  for (const char* set : {"multifile-master", "multifile-companion"}) {
    for (const auto& f : fs::directory_iterator(kData + "/ome-tiff/" + set)) {
      CAPTURE(f.path().string());
      auto s = open_ok(f.path().string());
      CHECK(s->info().dims == std::array<uint64_t, 3>{18, 24, 5});
      CHECK(s->info().dtype == DType::kU8);
      CHECK(s->info().channels == 1);
      CHECK(s->info().timepoints == 1);
      CHECK(s->format_name() == "OME-TIFF (5 files)");
      planes.push_back(read_all(*s, 0));
    }
  }
  for (const auto& p : planes) CHECK(p == planes[0]);
  // Plane z comes from multifile-Z{z+1}: each single-file read must match its z slice.
  auto all = open_ok(kData + "/ome-tiff/multifile-master/multifile-Z1.ome.tiff");
  const auto vol = read_all(*all, 0);
  bool distinct = false;
  for (int z = 0; z < 5; ++z) {
    const std::vector<uint8_t> plane(vol.begin() + z * 18 * 24, vol.begin() + (z + 1) * 18 * 24);
    if (z > 0) distinct |= plane != std::vector<uint8_t>(vol.begin(), vol.begin() + 18 * 24);
  }
  CHECK(distinct);
  // Signed int8 keeps negative values (the artificial planes use the whole range).
  auto zs = open_ok(kData + "/ome-tiff/z-series.ome.tif");
  const auto raw = read_all(*zs, 0);
  int8_t lo = 127;
  for (uint8_t v : raw) lo = std::min(lo, static_cast<int8_t>(v));
  CHECK(lo < 0);
}

TEST_CASE("importers: OME-XML PhysicalSize with units, converted when the axes disagree") {
  // Rewrite the companion XML with physical sizes in nm and mixed units; data files stay the same.
  const fs::path dir = scratch("ome_units");
  for (const auto& f : fs::directory_iterator(kData + "/ome-tiff/multifile-companion"))
    fs::copy_file(f.path(), dir / f.path().filename());
  std::ifstream in(dir / "multifile.companion.ome");
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const std::string key = "SizeZ=\"5\"";
  auto with = [&](const std::string& attrs) {
    std::string x = xml;
    x.insert(x.find(key) + key.size(), " " + attrs);
    std::ofstream(dir / "multifile.companion.ome", std::ios::trunc) << x;
    return open_ok((dir / "multifile.companion.ome").string());
  };
  auto a = with("PhysicalSizeX=\"65\" PhysicalSizeXUnit=\"nm\" PhysicalSizeY=\"65\" PhysicalSizeYUnit=\"nm\" "
                "PhysicalSizeZ=\"200\" PhysicalSizeZUnit=\"nm\"");
  CHECK(a->info().unit == "nm");
  CHECK(a->info().voxel_size == std::array<double, 3>{65, 65, 200});
  auto b = with("PhysicalSizeX=\"0.1\" PhysicalSizeY=\"0.1\" PhysicalSizeZ=\"2\" PhysicalSizeZUnit=\"\xC2\xB5m\"");
  CHECK(b->info().unit == "um");  // default unit is µm
  CHECK(b->info().voxel_size[2] == doctest::Approx(2.0));
  auto c = with("PhysicalSizeX=\"100\" PhysicalSizeXUnit=\"nm\" PhysicalSizeY=\"100\" PhysicalSizeYUnit=\"nm\" "
                "PhysicalSizeZ=\"0.002\" PhysicalSizeZUnit=\"mm\"");
  CHECK(c->info().unit == "um");
  CHECK(c->info().voxel_size[0] == doctest::Approx(0.1));
  CHECK(c->info().voxel_size[2] == doctest::Approx(2.0));
}

TEST_CASE("importers: Imaris .ims level 0, cropped to ImageSize, voxel size from ExtMin/ExtMax") {
  // SOURCES.md: 128x128x1 u16, ExtMin/Max X,Y 3..10, Z 0..0.1.
  check_info({"imaris/Minimal_IMS_File.ims", 128, 128, 1, DType::kU16, 1, 1, 7.0 / 128, 7.0 / 128, 0.1, "um"});
  auto s = open_ok(kData + "/imaris/Minimal_IMS_File.ims");
  const auto v = read_all(*s, 0);
  uint16_t first;
  std::memcpy(&first, v.data(), 2);
  CHECK(first == 88);
}

TEST_CASE("importers: ImageJ descriptions and unit spellings") {
  auto m = parse_imagej_description("ImageJ=1.54f\nimages=30\nchannels=2\nslices=5\nframes=3\nhyperstack=true\n"
                                    "unit=\\u00B5m\nloop=false\n");
  REQUIRE(m);
  CHECK(m->channels == 2);
  CHECK(m->slices == 5);
  CHECK(m->frames == 3);
  CHECK(m->spacing == 1.0);  // missing spacing means 1
  CHECK(parse_length_unit(m->unit)->name == "um");
  CHECK_FALSE(parse_imagej_description("OME something"));
  for (const char* u : {"um", "micron", "microns", "micrometer", "Micrometre", "\xC2\xB5m", "\xB5m", "\xCE\xBCm", "\\u00B5m"})
    CHECK_MESSAGE(parse_length_unit(u).value_or(LengthUnit{"?", 0}).name == "um", u);
  CHECK(parse_length_unit("nm")->um == doctest::Approx(1e-3));
  CHECK(parse_length_unit("mm")->um == doctest::Approx(1e3));
  CHECK_FALSE(parse_length_unit("pixel"));
  CHECK_FALSE(parse_length_unit(""));
}

TEST_CASE("importers: slice series sort naturally, from a folder, a glob or a file list") {
  CHECK(natural_less("img2.png", "img10.png"));
  CHECK_FALSE(natural_less("img10.png", "img2.png"));
  CHECK(natural_less("a-0009.tif", "a-0010.tif"));
  CHECK(natural_less("Slice1.png", "slice2.png"));
  // PNG slices whose value is their number: z order must follow 1, 2, ..., 12.
  const fs::path dir = scratch("png_natural");
  for (int i = 1; i <= 12; ++i) {
    ImageRgba8 img(8, 6);
    for (size_t k = 0; k < img.pixels.size(); ++k) img.pixels[k] = uint8_t(i * 10 + k % 4);
    REQUIRE(write_png((dir / ("img" + std::to_string(i) + ".png")).string(), img).is_ok());
  }
  std::ofstream(dir / "notes.txt") << "not a slice";
  for (const std::vector<std::string>& in :
       {std::vector<std::string>{dir.string()}, std::vector<std::string>{(dir / "img*.png").string()},
        std::vector<std::string>{(dir / "img10.png").string(), (dir / "img2.png").string(), (dir / "img1.png").string()}}) {
    auto s = open_ok(in);
    const bool all = in.size() == 1;
    CHECK(s->info().dims == std::array<uint64_t, 3>{8, 6, all ? 12u : 3u});
    CHECK(s->info().channels == 4);  // RGBA PNG: one channel per sample
    CHECK(s->info().dtype == DType::kU8);
    const auto green = read_all(*s, 1);
    const std::vector<int> order = all ? std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12} : std::vector<int>{1, 2, 10};
    for (size_t z = 0; z < order.size(); ++z) CHECK(green[z * 48] == order[z] * 10 + 1);
  }
  // JPEG slices (grey, quality 100: a flat picture decodes exactly).
  const fs::path jdir = scratch("jpeg_slices");
  for (int i = 0; i < 3; ++i) {
    std::string name = "s";
    name += std::to_string(i);
    write_gray_jpeg(jdir / (name + ".jpg"), 16, 9, uint8_t(40 * i + 20));
  }
  auto j = open_ok(jdir.string());
  CHECK(j->info().dims == std::array<uint64_t, 3>{16, 9, 3});
  CHECK(j->info().channels == 1);
  CHECK(j->format_name() == "JPEG slice series");
  const auto jv = read_all(*j, 0);
  CHECK(jv[0] == 20);
  CHECK(jv[16 * 9] == 60);
  CHECK(jv[2 * 16 * 9 + 5] == 100);
}

TEST_CASE("importers: bad input gives one line naming the file and the problem") {
  const fs::path dir = scratch("bad_input");
  auto one_line = [](const std::string& m) { return m.find('\n') == std::string::npos && !m.empty(); };

  SUBCASE("truncated TIFF") {
    const fs::path p = dir / "truncated.tif";
    fs::copy_file(kData + "/slices/mri-stack/mri-stack-0000.tif", p);
    fs::resize_file(p, fs::file_size(p) / 2);
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find(p.string() + ": page 0: image data runs past the end of the file") == 0, e);
    CHECK(one_line(e));
    // A stack cut in the middle of its directories fails too.
    const fs::path q = dir / "truncated-stack.tif";
    fs::copy_file(kData + "/tiff/mri-stack-calibrated.tif", q);
    fs::resize_file(q, fs::file_size(q) * 6 / 10);
    const std::string e2 = error_of({q.string()});
    CHECK_MESSAGE(e2.find(q.string() + ": page ") == 0, e2);
    CHECK_MESSAGE(e2.find("the file is truncated or damaged") != std::string::npos, e2);
  }
  SUBCASE("TIFF claiming absurd dimensions") {
    const fs::path p = dir / "absurd.tif";
    fs::copy_file(kData + "/slices/mri-stack/mri-stack-0000.tif", p);
    patch_tag(p, 256, 0xFFFFFFF0u);  // ImageWidth
    patch_tag(p, 257, 0xFFFFFFF0u);  // ImageLength
    patch_tag(p, 278, 0xFFFFFFFFu);  // RowsPerStrip: one strip, so libtiff accepts the directory
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find(p.string() + ": claims absurd dimensions (4294967280 x 4294967280") == 0, e);
    CHECK(one_line(e));
    // A size that does not overflow yet cannot be true: 2^31 x 2^31 pixels in a 42 kB file.
    const fs::path q = dir / "absurd2.tif";
    fs::copy_file(kData + "/slices/mri-stack/mri-stack-0000.tif", q);
    patch_tag(q, 256, 0x80000000u);
    patch_tag(q, 257, 0x80000000u);
    patch_tag(q, 278, 0x80000000u);
    const std::string e2 = error_of({q.string()});
    CHECK_MESSAGE(e2.find(q.string() + ": ") == 0, e2);
    CHECK_MESSAGE(e2.find("absurd dimensions") != std::string::npos, e2);
    CHECK(one_line(e2));
  }
  SUBCASE("non-TIFF named .tif") {
    const fs::path p = dir / "fake.tif";
    std::ofstream(p) << "this is a text file, not an image\n";
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find("fake.tif: not a TIFF file") != std::string::npos, e);
    CHECK(one_line(e));
  }
  SUBCASE("empty folder") {
    const fs::path p = dir / "empty";
    fs::create_directories(p);
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find("empty: folder holds no") != std::string::npos, e);
    CHECK(one_line(e));
  }
  SUBCASE("slice folder with mixed sizes names the odd file") {
    const fs::path p = dir / "mixed";
    fs::create_directories(p);
    for (const char* n : {"mri-stack-0000.tif", "mri-stack-0001.tif", "mri-stack-0003.tif"})
      fs::copy_file(kData + "/slices/mri-stack/" + n, p / n);
    fs::copy_file(kData + "/tiff/shapes_uncompressed.tif", p / "mri-stack-0002.tif");
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find("mri-stack-0002.tif: is 128x72") != std::string::npos, e);
    CHECK_MESSAGE(e.find("186x226") != std::string::npos, e);
    CHECK(one_line(e));
  }
  SUBCASE(".ims without DataSet") {
    const fs::path p = dir / "nodataset.ims";
    fs::copy_file(kData + "/imaris/Minimal_IMS_File.ims", p);
    const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    REQUIRE(H5Ldelete(f, "DataSet", H5P_DEFAULT) >= 0);
    H5Fclose(f);
    const std::string e = error_of({p.string()});
    CHECK_MESSAGE(e.find("nodataset.ims: has no DataSet group") != std::string::npos, e);
    CHECK(one_line(e));
  }
  SUBCASE("missing file, and a glob that matches nothing") {
    CHECK(error_of({(dir / "nope.tif").string()}).find("nope.tif: no such file") != std::string::npos);
    CHECK(error_of({(dir / "nope*.png").string()}).find("matches no files") != std::string::npos);
  }
}

namespace {

// Imaris-style attribute: a char array, one element per character.
void ims_attr(hid_t loc, const char* name, const std::string& value) {
  const hsize_t n = value.size();
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, 1);
  const hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, type, value.data());
  H5Aclose(a);
  H5Tclose(type);
  H5Sclose(space);
}

// A small .ims: 2 channels x 2 timepoints of u16, image 13x7x3 stored padded to
// 16x8x4 chunks; voxel (t, c, z, y, x) = t*1000 + c*100 + z*10 + (x+y) % 10,
// padding 65535. `filter`: an extra HDF5 filter id on channel 1 (0: none).
bool write_small_ims(const fs::path& p, H5Z_filter_t filter) {
  const hid_t f = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t info = H5Gcreate2(f, "DataSetInfo", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t image = H5Gcreate2(info, "Image", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  for (auto [k, v] : {std::pair{"ImageSizeX", "13"}, {"ImageSizeY", "7"}, {"ImageSizeZ", "3"}, {"ExtMin0", "-5"},
                      {"ExtMax0", "8"}, {"ExtMin1", "0"}, {"ExtMax1", "3.5"}, {"ExtMin2", "1"}, {"ExtMax2", "7"},
                      {"Unit", "nm"}})
    ims_attr(image, k, v);
  H5Gclose(image);
  H5Gclose(info);
  bool ok = true;
  const hsize_t shape[3] = {4, 8, 16};
  for (int t = 0; t < 2; ++t)
    for (int c = 0; c < 2; ++c) {
      const std::string g = "DataSet/ResolutionLevel 0/TimePoint " + std::to_string(t) + "/Channel " + std::to_string(c);
      const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
      H5Pset_create_intermediate_group(lcpl, 1);
      const hid_t grp = H5Gcreate2(f, g.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT);
      const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
      H5Pset_chunk(dcpl, 3, shape);
      H5Pset_deflate(dcpl, 2);
      if (filter && c == 1) H5Pset_filter(dcpl, filter, H5Z_FLAG_OPTIONAL, 0, nullptr);
      const hid_t space = H5Screate_simple(3, shape, nullptr);
      const hid_t ds = H5Dcreate2(grp, "Data", H5T_NATIVE_UINT16, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
      ok = ok && ds >= 0;
      std::vector<uint16_t> v(4 * 8 * 16, 65535);
      for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 7; ++y)
          for (int x = 0; x < 13; ++x) v[(z * 8 + y) * 16 + x] = uint16_t(t * 1000 + c * 100 + z * 10 + (x + y) % 10);
      if (ds >= 0) ok = ok && H5Dwrite(ds, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0;
      if (ds >= 0) H5Dclose(ds);
      H5Sclose(space);
      H5Pclose(dcpl);
      H5Gclose(grp);
      H5Pclose(lcpl);
    }
  H5Fclose(f);
  return ok;
}

}  // namespace

TEST_CASE("importers: Imaris every channel and timepoint, cropped from chunk padding, units from the file") {
  const fs::path dir = scratch("ims_small");
  REQUIRE(write_small_ims(dir / "small.ims", 0));
  auto s = open_ok((dir / "small.ims").string());
  const VolumeInfo& i = s->info();
  CHECK(i.dims == std::array<uint64_t, 3>{13, 7, 3});
  CHECK(i.dtype == DType::kU16);
  CHECK(i.channels == 2);
  CHECK(i.timepoints == 2);
  CHECK(i.unit == "nm");
  CHECK(i.voxel_size[0] == doctest::Approx(1.0));
  CHECK(i.voxel_size[1] == doctest::Approx(0.5));
  CHECK(i.voxel_size[2] == doctest::Approx(2.0));
  for (uint32_t t = 0; t < 2; ++t)
    for (uint32_t c = 0; c < 2; ++c) {
      const auto raw = read_all(*s, c, t);
      size_t bad = 0;
      for (uint32_t z = 0; z < 3; ++z)
        for (uint32_t y = 0; y < 7; ++y)
          for (uint32_t x = 0; x < 13; ++x) {
            uint16_t v;
            std::memcpy(&v, &raw[2 * ((z * 7 + y) * 13 + x)], 2);
            bad += v != t * 1000 + c * 100 + z * 10 + (x + y) % 10;  // never the 65535 padding
          }
      CHECK(bad == 0);
    }
}

TEST_CASE("importers: Imaris DataSetInfo/Channel N Name, Color and ColorRange become the channel display metadata") {
  const fs::path dir = scratch("ims_channels");
  const fs::path path = dir / "named.ims";
  REQUIRE(write_small_ims(path, 0));
  {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    const hid_t info = H5Gopen2(f, "DataSetInfo", H5P_DEFAULT);
    const hid_t c0 = H5Gcreate2(info, "Channel 0", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ims_attr(c0, "Name", "Hoechst");
    ims_attr(c0, "Color", "0 0.5 1");
    ims_attr(c0, "ColorRange", "100 1800");
    H5Gclose(c0);
    const hid_t c1 = H5Gcreate2(info, "Channel 1", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ims_attr(c1, "Color", "1 0 0 0.5");  // not "r g b": ignored, not an error
    ims_attr(c1, "ColorRange", "5 5");     // empty range: ignored
    H5Gclose(c1);
    H5Gclose(info);
    H5Fclose(f);
  }
  auto s = open_ok(path.string());
  const VolumeInfo& i = s->info();
  REQUIRE(i.channel_display.size() == 2);
  CHECK(i.channel_display[0].name == "Hoechst");
  CHECK(i.channel_display[0].color == std::array<uint8_t, 3>{0, 128, 255});
  CHECK(i.channel_display[0].window == std::array<double, 2>{100, 1800});
  CHECK(i.channel_display[1].empty());
  // The real Imaris sample has no DataSetInfo/Channel groups: nothing stated.
  CHECK(open_ok(kData + "/imaris/Minimal_IMS_File.ims")->info().channel_display.empty());
}

TEST_CASE("importers: an Imaris file that needs the LZ4 filter (32004) says so when HDF5 lacks it") {
  if (H5Zfilter_avail(32004) > 0) {
    MESSAGE("this HDF5 has the LZ4 filter; nothing to check");
    return;
  }
  const fs::path dir = scratch("ims_lz4");
  if (!write_small_ims(dir / "lz4.ims", 32004)) {
    MESSAGE("this HDF5 cannot even record filter 32004 as optional; skipped");
    return;
  }
  const std::string e = error_of({(dir / "lz4.ims").string()});
  CHECK_MESSAGE(e.find((dir / "lz4.ims").string() + ": is compressed with the HDF5 LZ4 filter (32004)") == 0, e);
  CHECK(e.find('\n') == std::string::npos);
}

TEST_CASE("importers: read_region from several threads at once returns what serial reads return") {
  for (const char* f : {"tiff/shapes_lzw_tiled_planar.tif", "tiff/mri-stack-calibrated.tif",
                        "ome-tiff/multifile-companion/multifile.companion.ome", "imaris/Minimal_IMS_File.ims",
                        "slices/mri-stack"}) {
    CAPTURE(f);
    auto s = open_ok(kData + "/" + f);
    const VolumeInfo info = s->info();
    // Boxes: one z slab per task, cycling channels.
    struct Task {
      uint32_t c;
      Box3 box;
      std::vector<uint8_t> serial, parallel;
    };
    std::vector<Task> tasks;
    for (uint64_t z = 0; z < info.dims[2]; ++z) {
      Task t;
      t.c = uint32_t(z % info.channels);
      t.box.origin = {z % 3, 0, z};
      t.box.size = {info.dims[0] - z % 3, info.dims[1], 1};
      t.serial = read_box(*s, t.c, 0, t.box);
      tasks.push_back(std::move(t));
    }
    std::atomic<size_t> next{0};
    std::atomic<int> failures{0};
    auto worker = [&] {
      for (size_t k; (k = next.fetch_add(1)) < tasks.size() * 4;) {
        Task& t = tasks[k % tasks.size()];
        std::vector<uint8_t> buf(t.serial.size());
        if (!s->read_region(t.c, 0, t.box, buf).is_ok() || buf != t.serial) failures.fetch_add(1);
      }
    };
    std::vector<std::thread> threads;
    for (int i = 0; i < 4; ++i) threads.emplace_back(worker);
    for (auto& th : threads) th.join();
    CHECK(failures.load() == 0);
  }
}

namespace {

// A classic big-endian TIFF as ImageJ writes stacks over 4 GB: one IFD for
// the first plane, the other planes stored right after it. u16, w x h, n planes
// (plane i, pixel k = i * 1000 + k). `planes_written` < n makes it truncated.
void write_imagej_contiguous(const fs::path& p, uint32_t w, uint32_t h, uint32_t n, uint32_t planes_written,
                             const std::string& extra_description = "") {
  std::vector<uint8_t> b;
  auto u16 = [&](uint16_t v) { b.push_back(uint8_t(v >> 8)), b.push_back(uint8_t(v)); };
  auto u32 = [&](uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) b.push_back(uint8_t(v >> s));
  };
  const std::string desc = "ImageJ=1.54f\nimages=" + std::to_string(n) + "\nslices=" + std::to_string(n) +
                           "\nunit=micron\nspacing=2.5\n" + extra_description + "loop=false\n";
  const uint16_t entries = 10;
  const uint32_t ifd = 8, desc_off = ifd + 2 + entries * 12 + 4, data_off = desc_off + uint32_t(desc.size()) + 1;
  b.insert(b.end(), {'M', 'M', 0, 42});
  u32(ifd);
  u16(entries);
  auto entry = [&](uint16_t tag, uint16_t type, uint32_t count, uint32_t value) {
    u16(tag), u16(type), u32(count);
    if (type == 3 && count == 1) u16(uint16_t(value)), u16(0);
    else u32(value);
  };
  entry(256, 4, 1, w);
  entry(257, 4, 1, h);
  entry(258, 3, 1, 16);
  entry(259, 3, 1, 1);
  entry(262, 3, 1, 1);
  entry(270, 2, uint32_t(desc.size() + 1), desc_off);
  entry(273, 4, 1, data_off);
  entry(277, 3, 1, 1);
  entry(278, 4, 1, h);
  entry(279, 4, 1, w * h * 2);
  u32(0);
  b.insert(b.end(), desc.begin(), desc.end());
  b.push_back(0);
  for (uint32_t i = 0; i < planes_written; ++i)
    for (uint32_t k = 0; k < w * h; ++k) u16(uint16_t(i * 1000 + k));
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
}

}  // namespace

TEST_CASE("importers: ImageJ stacks over 4 GB (one IFD, planes stored contiguously) read every plane") {
  const fs::path dir = scratch("imagej_contiguous");
  write_imagej_contiguous(dir / "big.tif", 9, 5, 6, 6);
  auto s = open_ok((dir / "big.tif").string());
  CHECK(s->info().dims == std::array<uint64_t, 3>{9, 5, 6});
  CHECK(s->info().dtype == DType::kU16);
  CHECK(s->info().voxel_size[2] == doctest::Approx(2.5));
  CHECK(s->info().unit == "um");
  const auto v = read_all(*s, 0);
  size_t bad = 0;
  for (uint32_t i = 0; i < 6; ++i)
    for (uint32_t k = 0; k < 45; ++k) {
      uint16_t x;
      std::memcpy(&x, &v[2 * (i * 45 + k)], 2);
      bad += x != i * 1000 + k;
    }
  CHECK(bad == 0);
  // Hyperstack order (XYCZT) applies to the contiguous planes too: 2 channels x 3 slices.
  write_imagej_contiguous(dir / "hyper.tif", 9, 5, 6, 6, "channels=2\n");
  {
    std::string patched;
    // slices=6 in the helper; rewrite it so channels x slices = images.
    std::ifstream in(dir / "hyper.tif", std::ios::binary);
    patched.assign((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t at = patched.find("slices=6");
    REQUIRE(at != std::string::npos);
    patched[at + 7] = '3';
    in.close();
    std::ofstream(dir / "hyper.tif", std::ios::binary | std::ios::trunc) << patched;
  }
  auto h = open_ok((dir / "hyper.tif").string());
  CHECK(h->info().channels == 2);
  CHECK(h->info().dims[2] == 3);
  Box3 b;
  b.origin = {0, 0, 2};
  b.size = {1, 1, 1};
  const auto px = read_box(*h, 1, 0, b);  // c1 z2 = plane 2*2+1 = 5
  uint16_t x;
  std::memcpy(&x, px.data(), 2);
  CHECK(x == 5000);
  // Fewer planes in the file than the description says: truncated, one line naming the file.
  write_imagej_contiguous(dir / "short.tif", 9, 5, 6, 4);
  const std::string e = error_of({(dir / "short.tif").string()});
  CHECK_MESSAGE(e.find((dir / "short.tif").string() + ": ImageJ metadata says 6 images") == 0, e);
  CHECK(e.find("truncated") != std::string::npos);
}

namespace {

// A 3-page 1024x1024 u16 TIFF made with libtiff: tiled 64x64 or strips of 16 rows, with `compression`.
void write_big_tiff_stack(const fs::path& p, bool tiled, uint16_t compression) {
  TIFF* t = TIFFOpen(p.c_str(), "w");
  REQUIRE(t);
  std::vector<uint16_t> buf(64 * 64);
  for (uint32_t z = 0; z < 3; ++z) {
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, 1024u);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, 1024u);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, uint16_t(16));
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, uint16_t(1));
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(t, TIFFTAG_COMPRESSION, compression);
    auto value = [z](uint32_t x, uint32_t y) { return uint16_t(z * 7 + x * 3 + y * 5); };
    if (tiled) {
      TIFFSetField(t, TIFFTAG_TILEWIDTH, 64u);
      TIFFSetField(t, TIFFTAG_TILELENGTH, 64u);
      for (uint32_t ty = 0; ty < 1024; ty += 64)
        for (uint32_t tx = 0; tx < 1024; tx += 64) {
          for (uint32_t y = 0; y < 64; ++y)
            for (uint32_t x = 0; x < 64; ++x) buf[y * 64 + x] = value(tx + x, ty + y);
          REQUIRE(TIFFWriteTile(t, buf.data(), tx, ty, 0, 0) > 0);
        }
    } else {
      TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, 16u);
      std::vector<uint16_t> row(1024);
      for (uint32_t y = 0; y < 1024; ++y) {
        for (uint32_t x = 0; x < 1024; ++x) row[x] = value(x, y);
        REQUIRE(TIFFWriteScanline(t, row.data(), y, 0) >= 0);
      }
    }
    REQUIRE(TIFFWriteDirectory(t));
  }
  TIFFClose(t);
}

}  // namespace

TEST_CASE("importers: a small box decodes only the strips/tiles under it, never the whole stack") {
  const fs::path dir = scratch("box_cost");
  struct Case {
    const char* name;
    bool tiled;
    uint16_t compression;
  };
  for (const Case& c : {Case{"tiled_deflate.tif", true, COMPRESSION_ADOBE_DEFLATE},
                        Case{"strips_lzw.tif", false, COMPRESSION_LZW}, Case{"strips_raw.tif", false, COMPRESSION_NONE},
                        Case{"tiled_raw.tif", true, COMPRESSION_NONE}}) {
    CAPTURE(c.name);
    write_big_tiff_stack(dir / c.name, c.tiled, c.compression);
    auto s = open_ok((dir / c.name).string());
    REQUIRE(s->info().dims == std::array<uint64_t, 3>{1024, 1024, 3});
    Box3 b;
    b.origin = {500, 500, 1};
    b.size = {10, 10, 1};  // inside tile (7, 7) / strip 31
    auto& counters = tiff::read_counters();
    const uint64_t blocks0 = counters.blocks_decoded, raw0 = counters.raw_bytes;
    const auto v = read_box(*s, 0, 0, b);
    const uint64_t blocks = counters.blocks_decoded - blocks0, raw = counters.raw_bytes - raw0;
    if (c.compression == COMPRESSION_NONE) {
      CHECK(blocks == 0);
      CHECK(raw == 10 * (c.tiled ? 64 : 1024) * 2);  // only the 10 rows asked for
    } else {
      CHECK(blocks == 1);
      CHECK(raw == 0);
    }
    uint16_t px;
    std::memcpy(&px, &v[2 * (3 * 10 + 4)], 2);
    CHECK(px == uint16_t(7 + 504 * 3 + 503 * 5));
  }
}

TEST_CASE("importers: a multi-file OME-TIFF with a missing part names the missing file") {
  const fs::path dir = scratch("ome_missing");
  for (const auto& f : fs::directory_iterator(kData + "/ome-tiff/multifile-master"))
    if (f.path().filename() != "multifile-Z4.ome.tiff") fs::copy_file(f.path(), dir / f.path().filename());
  const std::string e = error_of({(dir / "multifile-Z2.ome.tiff").string()});
  CHECK_MESSAGE(e.find((dir / "multifile-Z4.ome.tiff").string() + ": missing") == 0, e);
  CHECK(e.find("multifile-Z1.ome.tiff") != std::string::npos);  // the file whose XML names it
}

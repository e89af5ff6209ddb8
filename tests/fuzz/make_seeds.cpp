// Writes the small generated seed files of tests/fuzz/corpus (TIFF variants,
// a JPEG and PNG slice, raw sidecars, codec payloads). Not part of the build;
// the corpus is committed. Rebuild and rerun with:
//   g++ -std=c++20 -O1 tests/fuzz/make_seeds.cpp -o /tmp/make_seeds -ltiff -ljpeg -lpng -llz4 \
//     && /tmp/make_seeds tests/fuzz/corpus
// (real third-party seeds, copied from ../shared/testdata, sit beside these; the
// container seeds are `vxr import <a tiff seed> -o X.vxc --chunk 8`, one with
// --codec raw, one of a 9^3 all-zero f32 raw sidecar: uniform chunks; channels_v2.vxc
// is ome-tiff/multifile-master imported so: a version-2 header with a channel record.)
#include <cstddef>
#include <cstdio>

#include <jpeglib.h>
#include <lz4.h>
#include <png.h>
#include <tiffio.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

std::string root;

struct TiffSpec {
  const char* name;
  uint32_t w = 16, h = 12, pages = 1;
  uint16_t spp = 1, bps = 8, format = SAMPLEFORMAT_UINT, compression = COMPRESSION_NONE;
  uint16_t planar = PLANARCONFIG_CONTIG, photometric = PHOTOMETRIC_MINISBLACK, predictor = 1;
  bool big = false, big_endian = false, tiled = false;
  uint32_t rows_per_strip = 5;
  const char* description = nullptr;
};

void write_tiff(const TiffSpec& s) {
  const std::string path = root + "/tiff/" + s.name;
  std::string mode = "w";
  if (s.big) mode += "8";
  mode += s.big_endian ? "b" : "l";
  TIFF* t = TIFFOpen(path.c_str(), mode.c_str());
  if (!t) std::exit(1);
  for (uint32_t p = 0; p < s.pages; ++p) {
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, s.w);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, s.h);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, s.spp);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, s.bps);
    TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, s.format);
    TIFFSetField(t, TIFFTAG_COMPRESSION, s.compression);
    TIFFSetField(t, TIFFTAG_PLANARCONFIG, s.planar);
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, s.photometric);
    if (s.predictor != 1) TIFFSetField(t, TIFFTAG_PREDICTOR, s.predictor);
    if (s.description && p == 0) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, s.description);
    TIFFSetField(t, TIFFTAG_XRESOLUTION, 2000.0f);
    TIFFSetField(t, TIFFTAG_YRESOLUTION, 2000.0f);
    TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_CENTIMETER);
    if (s.photometric == PHOTOMETRIC_PALETTE) {
      std::vector<uint16_t> r(1u << s.bps), g(r.size()), b(r.size());
      for (size_t i = 0; i < r.size(); ++i) r[i] = uint16_t(i * 4099), g[i] = uint16_t(65535 - i * 999), b[i] = 257;
      TIFFSetField(t, TIFFTAG_COLORMAP, r.data(), g.data(), b.data());
    }
    if (s.pages > 1) TIFFSetField(t, TIFFTAG_SUBFILETYPE, 0);
    if (s.tiled) {
      TIFFSetField(t, TIFFTAG_TILEWIDTH, 16);
      TIFFSetField(t, TIFFTAG_TILELENGTH, 16);
      const tmsize_t ts = TIFFTileSize(t);
      std::vector<uint8_t> buf(ts);
      for (uint32_t i = 0; i < TIFFNumberOfTiles(t); ++i) {
        for (tmsize_t k = 0; k < ts; ++k) buf[k] = uint8_t(k * 7 + i + p);
        TIFFWriteEncodedTile(t, i, buf.data(), ts);
      }
    } else {
      TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, s.rows_per_strip);
      const tmsize_t ss = TIFFStripSize(t);
      std::vector<uint8_t> buf(ss);
      for (uint32_t i = 0; i < TIFFNumberOfStrips(t); ++i) {
        for (tmsize_t k = 0; k < ss; ++k) buf[k] = uint8_t((k / 3) * 5 + i + p);
        TIFFWriteEncodedStrip(t, i, buf.data(), ss);
      }
    }
    TIFFWriteDirectory(t);
  }
  TIFFClose(t);
}

void write_file(const std::string& rel, const std::vector<uint8_t>& bytes) {
  std::ofstream(root + "/" + rel, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

void write_jpeg(const std::string& rel) {
  jpeg_compress_struct c;
  jpeg_error_mgr e;
  c.err = jpeg_std_error(&e);
  jpeg_create_compress(&c);
  unsigned char* mem = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&c, &mem, &size);
  c.image_width = 16, c.image_height = 8, c.input_components = 1, c.in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(&c);
  jpeg_set_quality(&c, 50, TRUE);
  jpeg_start_compress(&c, TRUE);
  std::vector<uint8_t> row(16);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 16; ++x) row[x] = uint8_t(x * 16 + y);
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&c, &r, 1);
  }
  jpeg_finish_compress(&c);
  write_file(rel, std::vector<uint8_t>(mem, mem + size));
  jpeg_destroy_compress(&c);
  std::free(mem);
}

void write_png(const std::string& rel, int bit_depth, int color) {
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  img.width = 12, img.height = 6;
  img.format = (bit_depth == 16 ? PNG_FORMAT_FLAG_LINEAR : 0) | (color ? PNG_FORMAT_FLAG_COLOR : 0);
  const size_t n = PNG_IMAGE_SIZE(img);
  std::vector<uint8_t> px(n);
  for (size_t i = 0; i < n; ++i) px[i] = uint8_t(i * 13);
  png_alloc_size_t size = 0;
  png_image_write_to_memory(&img, nullptr, &size, 0, px.data(), 0, nullptr);
  std::vector<uint8_t> out(size);
  png_image_write_to_memory(&img, out.data(), &size, 0, px.data(), 0, nullptr);
  out.resize(size);
  write_file(rel, out);
}

void write_sidecar(const std::string& rel, const std::string& json, size_t raw_bytes) {
  std::vector<uint8_t> b(json.begin(), json.end());
  b.push_back(0);
  for (size_t i = 0; i < raw_bytes; ++i) b.push_back(uint8_t(i * 3));
  write_file(rel, b);
}

void write_codec(const std::string& rel, uint8_t codec, uint8_t dtype, uint8_t edge_byte, double value,
                 const std::vector<uint8_t>& stored) {
  std::vector<uint8_t> b = {codec, dtype, edge_byte};
  b.resize(11);
  std::memcpy(b.data() + 3, &value, 8);
  b.insert(b.end(), stored.begin(), stored.end());
  write_file(rel, b);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  root = argv[1];
  for (const char* d : {"tiff", "slices", "raw_sidecar", "codec"}) std::filesystem::create_directories(root + "/" + d);
  TIFFSetWarningHandler(nullptr);
  write_tiff({.name = "u8_two_pages.tif", .pages = 2});
  write_tiff({.name = "u16_big_endian.tif", .bps = 16, .big_endian = true});
  write_tiff({.name = "u8_bigtiff.tif", .big = true});
  write_tiff({.name = "u8_deflate_predictor.tif", .compression = COMPRESSION_ADOBE_DEFLATE, .predictor = 2});
  write_tiff({.name = "u8_lzw_tiled.tif", .w = 20, .h = 18, .compression = COMPRESSION_LZW, .tiled = true});
  write_tiff({.name = "u8_packbits.tif", .compression = COMPRESSION_PACKBITS});
  write_tiff({.name = "palette_4bit.tif", .bps = 4, .photometric = PHOTOMETRIC_PALETTE});
  write_tiff({.name = "rgb_planar.tif", .spp = 3, .planar = PLANARCONFIG_SEPARATE, .photometric = PHOTOMETRIC_RGB});
  write_tiff({.name = "f32_zstd.tif", .bps = 32, .format = SAMPLEFORMAT_IEEEFP, .compression = COMPRESSION_ZSTD});
  write_tiff({.name = "i16_12bit.tif", .bps = 12, .format = SAMPLEFORMAT_INT});
  write_tiff({.name = "imagej_hyperstack.tif", .pages = 4,
              .description = "ImageJ=1.53t\nimages=4\nchannels=2\nslices=2\nhyperstack=true\nunit=micron\nspacing=2.5\n"});
  write_tiff({.name = "ome_two_planes.ome.tif", .pages = 2,
              .description = "<?xml version=\"1.0\"?><OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">"
                             "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYZCT\" Type=\"uint8\" "
                             "SizeX=\"16\" SizeY=\"12\" SizeZ=\"2\" SizeC=\"1\" SizeT=\"1\" PhysicalSizeX=\"0.5\">"
                             "<Channel ID=\"Channel:0:0\" SamplesPerPixel=\"1\"/>"
                             "<TiffData IFD=\"0\" PlaneCount=\"2\"/></Pixels></Image></OME>"});
  write_jpeg("slices/gray.jpg");
  write_png("slices/gray8.png", 8, 0);
  write_png("slices/rgb16.png", 16, 1);
  write_sidecar("raw_sidecar/u8.bin", R"({"file": "vol.raw", "dims": [4, 3, 2], "dtype": "u8", "voxel_size": [1, 1, 2], "unit": "um"})", 24);
  write_sidecar("raw_sidecar/u16_big.bin", R"({"file": "vol.raw", "dims": [3, 2, 2], "dtype": "u16", "endian": "big", "channels": 2})", 48);
  write_sidecar("raw_sidecar/f32_time.bin", R"({"file": "vol.raw", "dims": [2, 2, 1], "dtype": "f32", "timepoints": 2})", 32);
  std::vector<uint8_t> raw(27);
  for (size_t i = 0; i < raw.size(); ++i) raw[i] = uint8_t(i);
  write_codec("codec/raw_u8.bin", 0, 0, 2, 0, raw);
  write_codec("codec/uniform_u16.bin", 3, 2, 7, 1234, {});
  write_codec("codec/uniform_f32.bin", 3, 6, 3, -0.5, {});
  std::vector<uint8_t> vox(4 * 4 * 4 * 2);
  for (size_t i = 0; i < vox.size(); ++i) vox[i] = uint8_t(i / 9);
  std::vector<uint8_t> lz(LZ4_compressBound(int(vox.size())));
  lz.resize(LZ4_compress_default(reinterpret_cast<const char*>(vox.data()), reinterpret_cast<char*>(lz.data()),
                                 int(vox.size()), int(lz.size())));
  write_codec("codec/lz4_u16.bin", 1, 2, 3, 0, lz);
  write_codec("codec/shuffle_lz4_u16.bin", 2, 2, 3, 0, lz);
  return 0;
}

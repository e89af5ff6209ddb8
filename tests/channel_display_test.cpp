// Channel names and colours as files state them (VolumeInfo::channel_display):
// parsed per format, kept by import in the .vxc header (version 2), read in
// place from OME-Zarr, shown by `vxr info`, and the session's default colour.
// The real file with a colour: ome-tiff/multifile-master (Channel Color
// -2147483648 = RGBA 0x80000000, dark red); no testdata file names a channel.
#include <doctest/doctest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.h"
#include "core/image.h"
#include "render/colormap.h"
#include "render/still_render.h"
#include "render/volume_session.h"
#include "volume/channel_display.h"
#include "volume/container_format.h"
#include "volume/container_layout.h"
#include "volume/container_reader.h"
#include "volume/container_verify.h"
#include "volume/importers/import_source.h"
#include "volume/memory_slab_source.h"
#include "volume/pyramid_builder.h"
#include "volume/zarr/zarr_chunk_source.h"

using namespace vxr;
using namespace vxr::test;
namespace fs = std::filesystem;

namespace {

const std::string kData = VXR_TESTDATA_DIR;
const std::string kColoured = kData + "/ome-tiff/multifile-master/multifile-Z1.ome.tiff";
const Rgb8 kDarkRed{128, 0, 0};

std::string q(const fs::path& p) { return shell_quote(p.string()); }

// Two u8 channels of 20x12x6 with the given display metadata.
MemorySlabSource two_channels(std::vector<ChannelDisplay> display) {
  VolumeInfo info;
  info.dims = {20, 12, 6};
  info.channels = 2;
  info.channel_display = std::move(display);
  std::vector<std::vector<uint8_t>> volumes;
  for (uint32_t c = 0; c < 2; ++c) {
    std::vector<uint8_t> v(info.voxels_per_volume());
    for (size_t i = 0; i < v.size(); ++i) v[i] = uint8_t((i * 7 + c * 50) % 256);
    volumes.push_back(std::move(v));
  }
  return MemorySlabSource(info, std::move(volumes));
}

uint32_t header_version(const fs::path& vxc) {
  std::ifstream f(vxc, std::ios::binary);
  vxc::FileHeader h{};
  f.read(reinterpret_cast<char*>(&h), sizeof h);
  return h.version;
}

}  // namespace

TEST_CASE("channel display: colours parse from the OME int, hex and Imaris spellings, names are cleaned") {
  CHECK(color_from_ome_int("-2147483648") == kDarkRed);  // RGBA 0x80000000
  CHECK(color_from_ome_int("-1") == Rgb8{255, 255, 255});
  CHECK(color_from_ome_int("65535") == Rgb8{0, 0, 255});  // 0x0000FFFF: blue, alpha 255
  CHECK(color_from_ome_int("4278190335") == Rgb8{255, 0, 0});  // unsigned spelling of 0xFF0000FF
  CHECK_FALSE(color_from_ome_int("red"));
  CHECK_FALSE(color_from_ome_int("4294967296"));
  CHECK(color_from_hex("00FF7f") == Rgb8{0, 255, 127});
  CHECK(color_from_hex("#0000ff") == Rgb8{0, 0, 255});
  CHECK_FALSE(color_from_hex("00FF7"));
  CHECK_FALSE(color_from_hex("00GG00"));
  CHECK(color_from_unit_floats("1 0.5 0") == Rgb8{255, 128, 0});
  CHECK_FALSE(color_from_unit_floats("1 0 2"));
  CHECK_FALSE(color_from_unit_floats("1 0"));
  CHECK(color_hex(Rgb8{128, 0, 255}) == "#8000ff");
  CHECK(clean_channel_name("  DAPI\t\n ") == "DAPI");
  const std::string long_name = std::string(62, 'a') + "\xC2\xB5" + "m";  // µ straddles byte 63
  CHECK(clean_channel_name(long_name) == std::string(62, 'a'));
  // "#rrggbb" is the single hue of that colour, as the generated ones are.
  CHECK(*find_colormap("#00ff00") == *find_colormap("green"));
  CHECK(find_colormap("#800000")->back() == glm::dvec3(128.0 / 255.0, 0, 0));
  CHECK_FALSE(find_colormap("800000"));
}

TEST_CASE("channel display: the multi-file OME-TIFF's Channel Color is read (master and companion)") {
  for (const std::string& path : {kColoured, kData + "/ome-tiff/multifile-companion/multifile.companion.ome"}) {
    CAPTURE(path);
    auto src = open_import_source({path});
    REQUIRE_MESSAGE(src.is_ok(), src.status().to_string());
    const VolumeInfo& i = (*src)->info();
    REQUIRE(i.channel_display.size() == 1);
    CHECK(i.channel_display[0].color == kDarkRed);
    CHECK(i.channel_display[0].name.empty());
  }
  // The single-file OME-TIFFs state neither (Channel elements without Name or Color).
  auto plain = open_import_source({kData + "/ome-tiff/multi-channel-z-series.ome.tif"});
  REQUIRE(plain.is_ok());
  CHECK((*plain)->info().channel_display.empty());
}

TEST_CASE("channel display: OME-XML Channel Name and Color of every channel") {
  const fs::path dir = scratch_dir("channel_display", "ome_xml");
  for (const auto& f : fs::directory_iterator(kData + "/ome-tiff/multifile-companion"))
    fs::copy_file(f.path(), dir / f.path().filename());
  std::ifstream in(dir / "multifile.companion.ome");
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  const std::string from = "Color=\"-2147483648\"";
  REQUIRE(xml.find(from) != std::string::npos);
  xml.replace(xml.find(from), from.size(), "Color=\"16711935\" Name=\" GFP \"");  // 0x00FF00FF: green
  std::ofstream(dir / "multifile.companion.ome", std::ios::trunc) << xml;
  auto src = open_import_source({(dir / "multifile.companion.ome").string()});
  REQUIRE_MESSAGE(src.is_ok(), src.status().to_string());
  REQUIRE((*src)->info().channel_display.size() == 1);
  CHECK((*src)->info().channel_display[0].name == "GFP");
  CHECK((*src)->info().channel_display[0].color == Rgb8{0, 255, 0});
}

TEST_CASE("channel display: import keeps names, colours and windows in a version 2 header, none writes version 1") {
  const fs::path dir = scratch_dir("channel_display", "container");
  ChannelDisplay dapi{"DAPI", Rgb8{0, 0, 255}, std::array<double, 2>{10, 200}};
  ChannelDisplay second;  // states nothing
  MemorySlabSource src = two_channels({dapi, second});
  ImportOptions opt;
  opt.chunk_size = 8;
  const fs::path out = dir / "named.vxc";
  auto sum = build_container(src, out.string(), opt);
  REQUIRE_MESSAGE(sum.is_ok(), sum.status().to_string());
  CHECK(header_version(out) == 2);
  auto r = ContainerReader::open(out.string());
  REQUIRE_MESSAGE(r.is_ok(), r.status().to_string());
  const VolumeInfo& i = (*r)->info();
  REQUIRE(i.channel_display.size() == 2);
  CHECK(i.channel_display[0].name == "DAPI");
  CHECK(i.channel_display[0].color == Rgb8{0, 0, 255});
  CHECK(i.channel_display[0].window == std::array<double, 2>{10, 200});
  CHECK(i.channel_display[1].empty());
  CHECK(verify_container(out.string()).ok());

  // Without metadata the file is the version-1 file older vxr reads.
  MemorySlabSource bare = two_channels({});
  const fs::path old = dir / "bare.vxc";
  REQUIRE(build_container(bare, old.string(), opt).is_ok());
  CHECK(header_version(old) == 1);
  auto r1 = ContainerReader::open(old.string());
  REQUIRE(r1.is_ok());
  CHECK((*r1)->info().channel_display.empty());

  // A damaged channel record is refused, naming the file, even with a fixed-up checksum.
  ContainerLayout L = (*r)->layout();
  std::vector<uint8_t> header = serialize_header(L);
  const size_t record0 = sizeof(vxc::FileHeader) + L.levels.size() * sizeof(vxc::LevelRecord) + sizeof(vxc::ChannelBlock);
  header[record0 + offsetof(vxc::ChannelRecord, flags)] |= 0x80;
  const uint64_t sum2 = vxc::checksum(header.data(), header.size() - 8);
  std::memcpy(header.data() + header.size() - 8, &sum2, 8);
  uint64_t bytes = 0;
  auto bad = parse_header(header, "crafted.vxc", &bytes);
  REQUIRE_FALSE(bad.is_ok());
  CHECK(bad.status().message().find("crafted.vxc: header channel record 0") != std::string::npos);
}

TEST_CASE("channel display: OME-Zarr omero channels are read in place, a mismatched list is ignored with a note") {
  const fs::path dir = scratch_dir("channel_display", "zarr");
  fs::copy(kData + "/zarr/simple_0.4", dir / "img.zarr", fs::copy_options::recursive);
  auto with_omero = [&](const nlohmann::json& omero) {
    std::ifstream in(kData + "/zarr/simple_0.4/.zattrs");
    nlohmann::json attrs = nlohmann::json::parse(in);
    attrs["omero"] = omero;
    std::ofstream(dir / "img.zarr" / ".zattrs", std::ios::trunc) << attrs.dump(2);
    auto src = ZarrChunkSource::open((dir / "img.zarr").string());
    REQUIRE_MESSAGE(src.is_ok(), src.status().to_string());
    return std::move(src).value();
  };
  auto src = with_omero({{"channels", {{{"label", "membrane"}, {"color", "FF00FF"}, {"window", {{"start", 5}, {"end", 900}}}}}}});
  REQUIRE(src->info().channel_display.size() == 1);
  CHECK(src->info().channel_display[0].name == "membrane");
  CHECK(src->info().channel_display[0].color == Rgb8{255, 0, 255});
  CHECK(src->info().channel_display[0].window == std::array<double, 2>{5, 900});
  // Wrong types are display hints gone wrong, not errors: skipped.
  auto odd = with_omero({{"channels", {{{"label", 7}, {"color", "pink"}}}}});
  CHECK(odd->info().channel_display.empty());
  auto two = with_omero({{"channels", {{{"color", "FF0000"}}, {{"color", "00FF00"}}}}});
  CHECK(two->info().channel_display.empty());
  bool noted = false;
  for (const std::string& w : two->warnings()) noted = noted || w.find("'omero'.'channels' lists 2") != std::string::npos;
  CHECK(noted);
}

TEST_CASE("channel display: the session draws a channel in the file's colour unless --colormap or settings choose") {
  SessionFlags none;
  auto s = open_volume_session(kColoured, none);
  REQUIRE_MESSAGE(s.is_ok(), s.status().to_string());
  REQUIRE(s->settings.channels.size() == 1);
  CHECK(s->settings.channels[0].colormap == "#800000");
  CHECK(s->source->info().channel_display.size() == 1);  // read whole through a DenseChunkSource, still described

  SessionFlags hot;
  hot.colormap = "hot";
  auto h = open_volume_session(kColoured, hot);
  REQUIRE(h.is_ok());
  CHECK(h->settings.channels[0].colormap == "hot");

  // The CPU reference picture (vxr render --reference) resolves the same colour.
  ReferenceStillOptions ro;
  ro.width = 16, ro.height = 16;
  auto still = render_still_reference(
      kColoured, none, [](const VolumePlacement& p, bool) -> Result<Camera> { return orbit_camera(p, 30, 25); }, ro);
  REQUIRE_MESSAGE(still.is_ok(), still.status().to_string());
  CHECK(still->settings == s->settings);

  // The same file imported: the container's header carries the colour to the same default.
  const fs::path dir = scratch_dir("channel_display", "session");
  auto src = open_import_source({kColoured});
  REQUIRE(src.is_ok());
  ImportOptions opt;
  opt.chunk_size = 16;
  REQUIRE(build_container(**src, (dir / "c.vxc").string(), opt).is_ok());
  auto c = open_volume_session((dir / "c.vxc").string(), none);
  REQUIRE_MESSAGE(c.is_ok(), c.status().to_string());
  CHECK(c->settings.channels[0].colormap == "#800000");
  CHECK(c->settings.channels[0].window_lo == s->settings.channels[0].window_lo);
  CHECK(c->settings.channels[0].window_hi == s->settings.channels[0].window_hi);

  // Several channels: the file's colour where stated, the generated hue elsewhere.
  {
    SettingsChoice choice;
    choice.settings = default_view_settings();
    std::vector<ChannelDisplay> display(3);
    display[1].color = Rgb8{255, 128, 0};
    SessionFlags f;
    auto drawn = resolve_drawn_settings(choice, f, "three", 3, 1,
                                        [](uint32_t) -> Result<std::pair<double, double>> { return std::pair{0.0, 1.0}; },
                                        display);
    REQUIRE(drawn.is_ok());
    CHECK(drawn->settings.channels[0].colormap == "green");
    CHECK(drawn->settings.channels[1].colormap == "#ff8000");
    CHECK(drawn->settings.channels[2].colormap == "cyan");
  }
}

TEST_CASE("channel display: vxr info shows it, and vxr render and vxr view draw the file's colour alike") {
  const fs::path dir = scratch_dir("channel_display", "cli");
  CliRun info = run_vxr("info " + q(kColoured), dir, 120);
  INFO(info.out << info.err);
  REQUIRE(info.rc == 0);
  CHECK(info.out.find("channel 0:   colour #800000") != std::string::npos);
  CliRun js = run_vxr("info --json " + q(kColoured), dir, 120);
  REQUIRE(js.rc == 0);
  const auto j = nlohmann::json::parse(js.out);
  CHECK(j.at("channel_display").at(0).at("color") == "#800000");

  CliRun imp = run_vxr("import " + q(kColoured) + " -o " + q(dir / "c.vxc"), dir, 120);
  REQUIRE_MESSAGE(imp.rc == 0, imp.out << imp.err);
  CliRun info_vxc = run_vxr("info " + q(dir / "c.vxc"), dir, 120);
  CHECK(info_vxc.out.find("channel 0:   colour #800000") != std::string::npos);

  // Seen from above the slices; no render section, so the colour is the default's: the file's.
  const std::string camera = R"({"camera": {"eye": [0, 0, 60], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y_deg": 40}})";
  std::ofstream(dir / "above.json") << camera;
  for (const std::string& input : {kColoured, (dir / "c.vxc").string()}) {
    CAPTURE(input);
    const std::string name = fs::path(input).stem().string();
    CliRun view = run_vxr("view " + q(input) + " --headless --frames 20 --width 48 --height 40 --settings " +
                              q(dir / "above.json") + " --png-dir " + q(dir / ("view_" + name)),
                          dir, 300);
    INFO(view.out << view.err);
    REQUIRE(view.rc == 0);
    CliRun render = run_vxr("render " + q(input) + " --size 48x40 --settings " + q(dir / "above.json") + " -o " +
                                q(dir / ("render_" + name + ".png")),
                            dir, 300);
    INFO(render.out << render.err);
    REQUIRE(render.rc == 0);
    CHECK(read_bytes(dir / ("render_" + name + ".png")) == read_bytes(dir / ("view_" + name) / "last_view.png"));
    auto png = read_png((dir / ("render_" + name + ".png")).string());
    REQUIRE(png.is_ok());
    // Dark red only: no green or blue anywhere, some red.
    bool red = false, other = false;
    for (size_t p = 0; p < png->pixels.size(); p += 4) {
      red = red || png->pixels[p] > 0;
      other = other || png->pixels[p + 1] > 0 || png->pixels[p + 2] > 0;
    }
    CHECK(red);
    CHECK_FALSE(other);
  }
}

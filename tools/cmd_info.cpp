// `vxr info`: what a .vxc container, an OME-Zarr image or any importable file holds.
#include <cstdio>
#include <nlohmann/json.hpp>

#include "command.h"
#include "volume/channel_display.h"
#include "volume/container_reader.h"
#include "volume/importers/import_source.h"
#include "volume/open_chunk_source.h"
#include "volume/zarr/zarr_chunk_source.h"

namespace vxr::cli {
namespace {

// What the file states about showing each channel, as JSON: one object per
// channel with the fields stated (name, color "#rrggbb", window [lo, hi]).
nlohmann::json channel_display_json(const VolumeInfo& i) {
  nlohmann::json list = nlohmann::json::array();
  for (uint32_t c = 0; c < i.channel_display.size(); ++c) {
    const ChannelDisplay& d = i.channel_display[c];
    nlohmann::json j = {{"channel", c}};
    if (!d.name.empty()) j["name"] = d.name;
    if (d.color) j["color"] = color_hex(*d.color);
    if (d.window) j["window"] = {(*d.window)[0], (*d.window)[1]};
    list.push_back(std::move(j));
  }
  return list;
}

// The fields every `info --json` has, whatever holds the volume (channel_display only when the file states it).
nlohmann::json volume_info_json(const VolumeInfo& i) {
  nlohmann::json j = {{"dims", {i.dims[0], i.dims[1], i.dims[2]}},
                      {"dtype", dtype_name(i.dtype)},
                      {"channels", i.channels},
                      {"timepoints", i.timepoints},
                      {"voxel_size", {i.voxel_size[0], i.voxel_size[1], i.voxel_size[2]}},
                      {"origin", {i.origin[0], i.origin[1], i.origin[2]}},
                      {"unit", i.unit}};
  if (!i.channel_display.empty()) j["channel_display"] = channel_display_json(i);
  return j;
}

// "name \"DAPI\", colour #0000ff, window 100..2000": what the file states about channel c.
std::string channel_display_text(const ChannelDisplay& d) {
  std::string s;
  auto add = [&](const std::string& part) { s += (s.empty() ? "" : ", ") + part; };
  if (!d.name.empty()) add("name \"" + d.name + "\"");
  if (d.color) add("colour " + color_hex(*d.color));
  if (d.window) {
    char w[80];
    std::snprintf(w, sizeof w, "window %g..%g", (*d.window)[0], (*d.window)[1]);
    add(w);
  }
  return s;
}

// The lines every text `info` has: dims, dtype, channels, timepoints, voxel size, origin (when set).
void print_volume_info_text(const VolumeInfo& i) {
  std::printf("dims:        %llu x %llu x %llu\n", (unsigned long long)i.dims[0], (unsigned long long)i.dims[1],
              (unsigned long long)i.dims[2]);
  std::printf("dtype:       %s\n", dtype_name(i.dtype));
  std::printf("channels:    %u\ntimepoints:  %u\n", i.channels, i.timepoints);
  std::printf("voxel size:  %g x %g x %g %s\n", i.voxel_size[0], i.voxel_size[1], i.voxel_size[2], i.unit.c_str());
  if (i.origin != std::array<double, 3>{0, 0, 0})
    std::printf("origin:      %g, %g, %g %s\n", i.origin[0], i.origin[1], i.origin[2], i.unit.c_str());
  for (uint32_t c = 0; c < i.channel_display.size(); ++c)
    if (!i.channel_display[c].empty())
      std::printf("%-13s%s\n", ("channel " + std::to_string(c) + ":").c_str(), channel_display_text(i.channel_display[c]).c_str());
}

// Units and paths come from files: bytes that are not UTF-8 print as U+FFFD instead of throwing.
void print_json(const nlohmann::json& j) {
  std::printf("%s\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
}

// An OME-Zarr folder: its metadata as read, and the levels the out-of-core renderer uses.
int describe_zarr(const std::string& path, bool as_json) {
  auto src = ZarrChunkSource::open(path);
  if (!src) return fail(src.status());
  const zarr::OmeZarrImage& img = (*src)->image();
  const VolumeInfo& i = img.info();
  const std::string format = (img.version().empty() ? std::string("Zarr array") : "OME-Zarr " + img.version()) +
                             " (Zarr v" + std::to_string(img.zarr_format()) + ")";
  if (as_json) {
    nlohmann::json j = volume_info_json(i);
    j["format"] = format;
    j["levels"] = img.levels().size();
    j["lod_levels"] = (*src)->levels().size();
    nlohmann::json levels = nlohmann::json::array();
    for (const auto& L : img.levels())
      levels.push_back({{"path", L.path},
                        {"dims", {L.dims[0], L.dims[1], L.dims[2]}},
                        {"factor", {L.factor[0], L.factor[1], L.factor[2]}},
                        {"zarr_chunks", L.array->meta().chunks},
                        {"sharded", L.array->meta().sharded}});
    j["level_info"] = levels;
    j["warnings"] = (*src)->warnings();
    print_json(j);
    return kExitOk;
  }
  std::printf("folder:      %s (%s)\n", path.c_str(), format.c_str());
  print_volume_info_text(i);
  std::printf("levels:      %zu (the out-of-core renderer uses %zu)\n", img.levels().size(), (*src)->levels().size());
  for (size_t l = 0; l < img.levels().size(); ++l) {
    const auto& L = img.levels()[l];
    std::string chunks;
    for (uint64_t c : L.array->meta().chunks) chunks += (chunks.empty() ? "" : "x") + std::to_string(c);
    std::printf("  %2zu: %s: %llu x %llu x %llu voxels, factor %g,%g,%g, zarr chunks %s%s\n", l, L.path.c_str(),
                (unsigned long long)L.dims[0], (unsigned long long)L.dims[1], (unsigned long long)L.dims[2],
                L.factor[0], L.factor[1], L.factor[2], chunks.c_str(), L.array->meta().sharded ? " (sharded)" : "");
  }
  for (const std::string& w : (*src)->warnings()) std::printf("note:        %s\n", w.c_str());
  return kExitOk;
}

// A file `vxr import` reads (TIFF, OME-TIFF, Imaris, a slice folder, raw + sidecar): what the importer sees,
// without importing it.
int describe_importable(const std::string& path, bool as_json) {
  auto src = open_import_source({path});
  if (!src) return fail(src.status());
  const SlabSource& s = **src;
  const VolumeInfo& i = s.info();
  if (as_json) {
    nlohmann::json j = volume_info_json(i);
    j["format"] = s.format_name();
    j["files"] = s.files().size();
    j["warnings"] = s.warnings();
    j["container"] = false;
    print_json(j);
    return kExitOk;
  }
  std::printf("file:        %s (%s)\n", path.c_str(), s.format_name().c_str());
  print_volume_info_text(i);
  if (s.files().size() > 1) std::printf("files:       %zu\n", s.files().size());
  for (const std::string& w : s.warnings()) std::printf("note:        %s\n", w.c_str());
  std::printf("note:        not a container: `vxr view`/`vxr render` read it as it is; `vxr import %s -o OUT.vxc`"
              " makes an out-of-core container\n", path.c_str());
  return kExitOk;
}

}  // namespace

void add_info_command(CLI::App& app, Invocation& inv) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("info", "describe a .vxc container, an OME-Zarr image or any importable file (dims, dtype, channels, levels, chunks)");
  cmd->add_option("file", *path, ".vxc file, OME-Zarr folder, or a file/folder `vxr import` reads")->required();
  cmd->add_flag("--json", *json, "print JSON");
  cmd->callback([&inv, path, json] {
    inv.run = [path, json] {
      if (zarr::looks_like_zarr(*path)) return describe_zarr(*path, *json);
      if (!is_chunk_source_input(*path)) return describe_importable(*path, *json);
      auto reader = ContainerReader::open(*path);
      if (!reader) return fail(reader.status());
      const ContainerReader& r = **reader;
      const VolumeInfo& i = r.info();
      const auto& L = r.layout();
      const uint64_t uniform = r.uniform_chunks();
      const char* codec_names[] = {"raw", "lz4", "shuffle-lz4", "uniform"};
      if (*json) {
        nlohmann::json j = volume_info_json(i);
        j["levels"] = r.levels().size();
        j["chunks"] = r.chunk_count();
        j["compression_ratio"] = r.compression_ratio();
        j["chunk_size"] = r.chunk_size();
        j["apron"] = r.apron();
        j["uniform_chunks"] = uniform;
        j["file_bytes"] = r.file_bytes();
        j["codec"] = codec_names[static_cast<int>(L.codec)];
        j["downsample"] = L.downsample == vxc::Downsample::kMax ? "max" : "mean";
        nlohmann::json levels = nlohmann::json::array();
        for (const auto& li : r.levels())
          levels.push_back({{"dims", {li.dims[0], li.dims[1], li.dims[2]}},
                            {"chunk_counts", {li.chunk_counts[0], li.chunk_counts[1], li.chunk_counts[2]}},
                            {"downsample", {li.downsample[0], li.downsample[1], li.downsample[2]}}});
        j["level_info"] = levels;
        print_json(j);
        return kExitOk;
      }
      std::printf("file:        %s (%llu bytes)\n", path->c_str(), (unsigned long long)r.file_bytes());
      print_volume_info_text(i);
      std::printf("chunks:      %llu of %u^3 (+%u apron), %llu uniform, codec %s\n", (unsigned long long)r.chunk_count(), r.chunk_size(),
                  r.apron(), (unsigned long long)uniform, codec_names[static_cast<int>(L.codec)]);
      std::printf("compression: %.2f : 1\n", r.compression_ratio());
      std::printf("levels:      %zu (%s downsampling)\n", r.levels().size(),
                  L.downsample == vxc::Downsample::kMax ? "max" : "mean");
      for (size_t l = 0; l < r.levels().size(); ++l) {
        const auto& li = r.levels()[l];
        std::printf("  %2zu: %llu x %llu x %llu voxels, %u x %u x %u chunks, downsample %u,%u,%u\n", l,
                    (unsigned long long)li.dims[0], (unsigned long long)li.dims[1], (unsigned long long)li.dims[2],
                    li.chunk_counts[0], li.chunk_counts[1], li.chunk_counts[2], li.downsample[0], li.downsample[1],
                    li.downsample[2]);
      }
      return kExitOk;
    };
  });
}

}  // namespace vxr::cli

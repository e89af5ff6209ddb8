#include "render/volume_session.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "annotate/project.h"
#include "assets/assets.h"
#include "render/transfer_function.h"
#include "volume/container_reader.h"
#include "volume/dense_chunk_source.h"
#include "volume/load_dense.h"
#include "volume/open_chunk_source.h"

namespace vxr {
namespace {


// The window of a chunked source from a level small enough to read whole.
Result<std::pair<double, double>> source_window(const ChunkSource& src) {
  const uint32_t level = finest_level_that_fits(src, 4096, uint64_t(2) << 20);
  VXR_ASSIGN_OR_RETURN(DenseVolume dense, read_level_dense(src, level, 0, 0, uint64_t(64) << 20));
  return percentile_window(dense);
}

Status apply_flags(const SessionFlags& f, RenderSettings& s) {
  if (!f.colormap.empty()) s.channels[0].colormap = f.colormap;
  if (!f.model.empty() && !optical_model_from_name(f.model, &s.model))
    return invalid_argument("--model: unknown optical model '" + f.model + "'");
  if (f.step != 0.0) {
    if (!(f.step > 0.0) || !std::isfinite(f.step)) return invalid_argument("--step: must be > 0 voxels");
    s.step_voxels = f.step;
  }
  if (!f.window.empty()) {
    std::stringstream ss(f.window);
    double lo = 0, hi = 0;
    char comma = 0;
    if (!(ss >> lo >> comma >> hi) || comma != ',' || !ss.eof() || !(hi > lo))
      return invalid_argument("--window: '" + f.window + "' is not LO,HI with LO < HI (data units)");
    s.channels[0].window_lo = lo;
    s.channels[0].window_hi = hi;
  }
  return Status::ok();
}

std::string dims_text(const VolumeInfo& i) {
  return std::string(dtype_name(i.dtype)) + " " + std::to_string(i.dims[0]) + "x" + std::to_string(i.dims[1]) + "x" +
         std::to_string(i.dims[2]);
}

}  // namespace

// Values at the 0.5 and 99.5 percentiles of a volume (sampled), in data units.
std::pair<double, double> percentile_window(const DenseVolume& v) {
  std::vector<double> s;
  const uint64_t n = v.voxel_count();
  const uint64_t stride = std::max<uint64_t>(1, n / 200000);
  for (uint64_t i = 0; i < n; i += stride) {
    const uint64_t x = i % v.dims[0], y = (i / v.dims[0]) % v.dims[1], z = i / (uint64_t(v.dims[0]) * v.dims[1]);
    s.push_back(v.value_at(uint32_t(x), uint32_t(y), uint32_t(z)));
  }
  std::sort(s.begin(), s.end());
  double lo = s[size_t(0.005 * double(s.size() - 1))], hi = s[size_t(0.995 * double(s.size() - 1))];
  if (!(hi > lo)) lo = s.front(), hi = s.back();
  if (!(hi > lo)) hi = lo + 1.0;
  return {lo, hi};
}

RenderSettings default_view_settings() {
  RenderSettings s;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 20;
  s.channels[0].window_hi = 220;
  s.step_voxels = 0.5;
  s.density = 0.08;
  return s;
}

Result<std::unique_ptr<ProceduralSource>> open_procedural(const std::string& spec) {
  std::vector<std::string> parts;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ':')) parts.push_back(item);
  auto bad = [&](const std::string& why) {
    return invalid_argument("input '" + spec + "': " + why +
                            "; use procedural:vessels:SIDE[:SEED], e.g. procedural:vessels:65536");
  };
  if (parts.size() < 3 || parts.size() > 4 || parts[1] != "vessels") return bad("unknown procedural source");
  ProceduralOptions po;
  char* end = nullptr;
  const unsigned long long side = std::strtoull(parts[2].c_str(), &end, 10);
  if (parts[2].empty() || *end != '\0' || side == 0 || side > (1ull << 17)) return bad("SIDE must be 1..131072 voxels");
  po.dims = {side, side, side};
  if (parts.size() == 4) {
    po.seed = std::strtoull(parts[3].c_str(), &end, 10);
    if (parts[3].empty() || *end != '\0') return bad("SEED must be a whole number");
  }
  po.noise_max = 6;  // as `vxr bench lod`: faint background below the default window
  auto src = ProceduralSource::create(po);
  if (!src) return bad(src.status().message());
  return src;
}

Result<VolumeSession> open_volume_session(const std::string& given, const SessionFlags& flags) {
  VolumeSession out;
  std::string input = given;
  out.annotation_store = flags.annotations;
  // A project folder: its volume, and its store unless another was named.
  std::error_code ec;
  if (!input.empty() && std::filesystem::exists(std::filesystem::path(input) / "project.json", ec)) {
    VXR_ASSIGN_OR_RETURN(annotate::ProjectInfo project, annotate::read_project(input));
    if (out.annotation_store.empty()) out.annotation_store = (std::filesystem::path(input) / project.annotations).string();
    input = (std::filesystem::path(input) / project.volume).string();
  }
  if (!out.annotation_store.empty() && !std::filesystem::is_directory(out.annotation_store, ec))
    return not_found(out.annotation_store + ": no annotation store here (make one with `vxr annotate init`)");
  out.settings = default_view_settings();
  bool window_known = false;
  if (input.empty()) {
    VXR_ASSIGN_OR_RETURN(DenseVolume v, assets::sample_volume());
    std::vector<DenseVolume> channels;
    channels.push_back(std::move(v));
    VXR_ASSIGN_OR_RETURN(out.source, DenseChunkSource::create(std::move(channels)));
    out.description = "the bundled sample";
    window_known = true;  // the defaults were chosen for it
  } else if (input.rfind("procedural:", 0) == 0) {
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<ProceduralSource> p, open_procedural(input));
    out.source = std::move(p);
    out.description = input;
    out.settings.channels[0].window_lo = 8;  // above the background noise (0..6), as `vxr render`
    out.settings.channels[0].window_hi = 200;
    window_known = true;
  } else if (is_chunk_source_input(input)) {  // .vxc, OME-Zarr: read in place
    VXR_ASSIGN_OR_RETURN(OpenedChunkSource opened, open_chunk_source(input));
    out.source = std::move(opened.source);
    out.notes = std::move(opened.warnings);
    out.description = input + " (" + opened.format + ")";
  } else {
    VXR_ASSIGN_OR_RETURN(LoadedVolume loaded, load_for_render(input, 1u << 20, flags.max_dense_bytes));
    out.notes = loaded.notes;
    out.description = input + " (" + loaded.format + ")";
    std::vector<std::vector<DenseVolume>> series;
    series.push_back(std::move(loaded.channels));
    for (auto& t : loaded.later_timepoints) series.push_back(std::move(t));
    VXR_ASSIGN_OR_RETURN(out.source, DenseChunkSource::create_series(std::move(series)));
  }
  const VolumeInfo& info = out.source->info();
  out.description += " (" + dims_text(info) + ", " + std::to_string(out.source->levels().size()) + " levels)";
  if (!window_known && flags.window.empty()) {
    VXR_ASSIGN_OR_RETURN(auto w, source_window(*out.source));
    out.settings.channels[0].window_lo = w.first;
    out.settings.channels[0].window_hi = w.second;
  }
  VXR_RETURN_IF_ERROR(apply_flags(flags, out.settings));
  VXR_RETURN_IF_ERROR(validate_render_settings(out.settings, 1));
  return out;
}

}  // namespace vxr

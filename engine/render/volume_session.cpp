#include "render/volume_session.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "annotate/project.h"
#include "assets/assets.h"
#include "render/transfer_function.h"
#include "volume/channel_display.h"
#include "volume/container_reader.h"
#include "volume/dense_chunk_source.h"
#include "volume/load_dense.h"
#include "volume/open_chunk_source.h"

namespace vxr {
namespace {


// "X,Y" -> the two finite numbers, when that is the whole text.
bool parse_pair(const std::string& text, double* first, double* second) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos) return false;
  char* end = nullptr;
  const std::string a = text.substr(0, comma), b = text.substr(comma + 1);
  *first = std::strtod(a.c_str(), &end);
  if (a.empty() || *end != '\0' || !std::isfinite(*first)) return false;
  *second = std::strtod(b.c_str(), &end);
  return !b.empty() && *end == '\0' && std::isfinite(*second);
}

// "X" -> X when the whole text is one finite number.
bool parse_number(const std::string& text, double* out) {
  char* end = nullptr;
  *out = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*out);
}

// --model --colormap --window --step --iso over the start's settings (channel 0's colour and window).
Status apply_flags(const SessionFlags& f, SettingsChoice& c) {
  RenderSettings& s = c.settings;
  if (!f.model.empty() && !optical_model_from_name(f.model, &s.model))
    return invalid_argument("--model: unknown optical model '" + f.model +
                            "' (use ea, emission, mip, minip, average or iso)");
  if (!f.colormap.empty()) s.channels[0].colormap = f.colormap, c.colormap_given = true;
  if (!f.window.empty()) {
    double lo = 0, hi = 0;
    if (!parse_pair(f.window, &lo, &hi)) return invalid_argument("--window: expected lo,hi, got '" + f.window + "'");
    if (!(hi > lo)) return invalid_argument("--window: lo " + f.window.substr(0, f.window.find(',')) + " must be below hi");
    s.channels[0].window_lo = lo;
    s.channels[0].window_hi = hi;
    c.window_given = true;
  }
  if (f.step != 0.0) s.step_voxels = f.step;
  if (!(s.step_voxels > 0.0) || !std::isfinite(s.step_voxels)) return invalid_argument("--step: must be > 0 voxels");
  if (!f.iso.empty()) {
    if (!parse_number(f.iso, &s.iso_value))
      return invalid_argument("--iso: expected one number (data units), got '" + f.iso + "'");
    if (f.model.empty()) s.model = OpticalModel::kIsosurface;
    c.iso_given = true;
  }
  return Status::ok();
}

// A source with another physical voxel size; chunks are forwarded untouched.
class VoxelSizeSource final : public ChunkSource {
 public:
  VoxelSizeSource(std::shared_ptr<const ChunkSource> inner, const std::array<double, 3>& voxel_size)
      : inner_(std::move(inner)), info_(inner_->info()) {
    info_.voxel_size = voxel_size;
  }
  const VolumeInfo& info() const override { return info_; }
  const std::vector<LevelInfo>& levels() const override { return inner_->levels(); }
  uint32_t chunk_size() const override { return inner_->chunk_size(); }
  uint32_t apron() const override { return inner_->apron(); }
  Result<ChunkStats> stats(const ChunkKey& key) const override { return inner_->stats(key); }
  Result<std::shared_ptr<const Chunk>> read(const ChunkKey& key) const override { return inner_->read(key); }

 private:
  std::shared_ptr<const ChunkSource> inner_;
  VolumeInfo info_;
};

std::string dims_text(const VolumeInfo& i) {
  return std::string(dtype_name(i.dtype)) + " " + std::to_string(i.dims[0]) + "x" + std::to_string(i.dims[1]) + "x" +
         std::to_string(i.dims[2]);
}

}  // namespace

Result<std::optional<std::array<double, 3>>> parse_voxel_size_flag(const std::string& text) {
  if (text.empty()) return std::optional<std::array<double, 3>>();
  std::array<double, 3> v{};
  std::stringstream ss(text);
  std::string item;
  int n = 0;
  bool ok = true;
  while (std::getline(ss, item, ',')) {
    if (n < 3) ok = ok && parse_number(item, &v[n]) && v[n] > 0.0;
    ++n;
  }
  if (!ok || n != 3 || text.back() == ',')
    return invalid_argument("--voxel-size: '" + text + "' is not X,Y,Z with three finite numbers > 0 (world units per voxel)");
  return std::optional<std::array<double, 3>>(v);
}

std::string voxel_size_text(const std::array<double, 3>& v) {
  std::ostringstream ss;
  ss.precision(17);
  ss << v[0] << ',' << v[1] << ',' << v[2];
  return ss.str();
}

Status apply_opacity_flags(const SessionFlags& f, RenderSettings& s) {
  if (!f.opacity.empty()) {
    // "LO:A,HI:B"
    double v[4] = {0, 0, 0, 0};
    const size_t comma = f.opacity.find(',');
    const std::string parts[2] = {f.opacity.substr(0, comma), comma == std::string::npos ? "" : f.opacity.substr(comma + 1)};
    bool ok = comma != std::string::npos;
    for (int i = 0; i < 2 && ok; ++i) {
      const size_t colon = parts[i].find(':');
      ok = colon != std::string::npos && parse_number(parts[i].substr(0, colon), &v[2 * i]) &&
           parse_number(parts[i].substr(colon + 1), &v[2 * i + 1]);
    }
    if (!ok)
      return invalid_argument("--opacity: '" + f.opacity + "' is not LO:A,HI:B (e.g. 0.1:0,0.9:1)");
    const double lo = v[0], a = v[1], hi = v[2], b = v[3];
    if (!(lo >= 0.0 && hi <= 1.0 && lo < hi))
      return invalid_argument("--opacity: '" + f.opacity + "': LO and HI are window fractions with 0 <= LO < HI <= 1");
    if (!(a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0))
      return invalid_argument("--opacity: '" + f.opacity + "': the opacities A and B must be within 0..1");
    std::vector<OpacityPoint> ramp;
    if (lo > 0.0) ramp.push_back({0.0, 0.0}), ramp.push_back({lo, 0.0});
    ramp.push_back({lo, a});
    ramp.push_back({hi, b});
    if (hi < 1.0) ramp.push_back({1.0, b});
    for (ChannelSettings& ch : s.channels) ch.opacity_points = ramp;
  }
  if (!f.opacity_unit_distance.empty()) {
    double d = 0.0;
    if (!parse_number(f.opacity_unit_distance, &d) || d < 0.0)
      return invalid_argument("--opacity-unit-distance: '" + f.opacity_unit_distance +
                              "' must be a finite number > 0 (world units), or 0 for opacity per voxel");
    s.opacity_unit_distance = d;
  }
  return Status::ok();
}

std::shared_ptr<const ChunkSource> with_voxel_size(std::shared_ptr<const ChunkSource> source,
                                                   const std::array<double, 3>& voxel_size) {
  return std::make_shared<VoxelSizeSource>(std::move(source), voxel_size);
}

Status apply_voxel_size_flag(const SessionFlags& f, uint32_t shrink, std::vector<DenseVolume>& channels) {
  VXR_ASSIGN_OR_RETURN(const auto voxel_size, parse_voxel_size_flag(f.voxel_size));
  if (!voxel_size) return Status::ok();
  for (DenseVolume& v : channels)
    for (int a = 0; a < 3; ++a) v.voxel_size[a] = (*voxel_size)[a] * (v.dims[a] > 1 ? double(shrink) : 1.0);
  return Status::ok();
}

Result<SettingsStart> read_settings_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return not_found(path + ": cannot open the settings file");
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  SettingsStart start;
  // A Scene has a render, camera or volume section; plain RenderSettings have none.
  start.is_scene = text.find("\"render\"") != std::string::npos || text.find("\"camera\"") != std::string::npos ||
                   text.find("\"volume\"") != std::string::npos;
  if (start.is_scene) {
    auto sc = scene_from_json(text);
    if (!sc) return invalid_argument(path + ": " + sc.status().message());
    start.scene = std::move(sc).value();
  } else {
    auto rs = render_settings_from_json(text);
    if (!rs) return invalid_argument(path + ": " + rs.status().message());
    start.scene.render = std::move(rs).value();
  }
  start.has_window = text.find("\"window\"") != std::string::npos;
  return start;
}

Result<SessionFlags> complete_session_flags(SessionFlags f) {
  if (!f.start && !f.settings.empty()) {
    VXR_ASSIGN_OR_RETURN(SettingsStart start, read_settings_file(f.settings));
    f.start = std::move(start);
  }
  if (!f.start || !f.start->is_scene) return f;
  const Scene& sc = f.start->scene;
  if (f.channel.empty())
    for (size_t i = 0; i < sc.channels.size(); ++i) f.channel += (i ? "," : "") + std::to_string(sc.channels[i]);
  if (!f.timepoint_given) f.timepoint = sc.timepoint, f.timepoint_given = true;
  if (f.voxel_size.empty() && sc.voxel_size[0] > 0.0) f.voxel_size = voxel_size_text(sc.voxel_size);
  if (f.annotations.empty()) f.annotations = sc.annotations;
  return f;
}

Result<SettingsChoice> choose_settings(const SessionFlags& given) {
  VXR_ASSIGN_OR_RETURN(const SessionFlags f, complete_session_flags(given));
  SettingsChoice c;
  if (f.start) {
    c.settings = f.start->scene.render;
    c.window_given = f.start->has_window;
    c.defaults = false;
  } else {
    c.settings = default_view_settings();
  }
  VXR_RETURN_IF_ERROR(parse_voxel_size_flag(f.voxel_size).status());
  VXR_RETURN_IF_ERROR(apply_flags(f, c));
  VXR_RETURN_IF_ERROR(apply_opacity_flags(f, c.settings));
  // What does not depend on the data (colormap names, windows, steps).
  VXR_RETURN_IF_ERROR(
      validate_render_settings(c.settings, static_cast<uint32_t>(std::max<size_t>(1, c.settings.channels.size()))));
  return c;
}

Result<std::vector<uint32_t>> parse_channel_flag(const std::string& text, const std::string& input,
                                                 uint32_t volume_channels) {
  std::vector<uint32_t> out;
  if (text.empty()) {
    for (uint32_t c = 0; c < std::min<uint32_t>(volume_channels, VXR_MAX_CHANNELS); ++c) out.push_back(c);
    return out;
  }
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const unsigned long c = std::strtoul(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || c >= volume_channels)
      return invalid_argument("--channel: '" + item + "', but " + input + " has " + std::to_string(volume_channels) +
                              " channel(s) (0.." + std::to_string(volume_channels - 1) + ")");
    if (std::find(out.begin(), out.end(), uint32_t(c)) != out.end())
      return invalid_argument("--channel: channel " + item + " is named twice");
    out.push_back(uint32_t(c));
  }
  if (out.size() > VXR_MAX_CHANNELS)
    return invalid_argument("--channel: at most " + std::to_string(VXR_MAX_CHANNELS) + " channels are drawn together");
  return out;
}

Status check_timepoint(const std::string& input, uint32_t timepoint, uint32_t timepoints) {
  if (timepoint < timepoints) return Status::ok();
  return invalid_argument("--timepoint: " + std::to_string(timepoint) + ", but " + input + " has " +
                          std::to_string(timepoints) + " timepoint(s) (0.." + std::to_string(timepoints - 1) + ")");
}

Result<DrawnSettings> resolve_drawn_settings(SettingsChoice choice, const SessionFlags& flags, const std::string& input,
                                             uint32_t volume_channels, uint32_t timepoints, const AutoWindow& auto_window,
                                             const std::vector<ChannelDisplay>& display) {
  DrawnSettings out;
  VXR_ASSIGN_OR_RETURN(out.channels, parse_channel_flag(flags.channel, input, volume_channels));
  VXR_RETURN_IF_ERROR(check_timepoint(input, flags.timepoint, timepoints));
  if (volume_channels > VXR_MAX_CHANNELS && flags.channel.empty())
    out.notes.push_back(std::to_string(volume_channels) + " channels; drawing 0.." + std::to_string(VXR_MAX_CHANNELS - 1) +
                        " (choose with --channel)");
  RenderSettings& s = choice.settings;
  const size_t n = out.channels.size();
  // Channels without settings get their own: a distinct colour each (a copy
  // of channel 0's settings otherwise, window included).
  const char* hues[4] = {"green", "magenta", "cyan", "yellow"};
  // The file's colour for drawn channel c, when it states one.
  auto file_color = [&](size_t c) -> std::optional<std::string> {
    const uint32_t source_channel = out.channels[c];
    if (source_channel >= display.size() || !display[source_channel].color) return std::nullopt;
    return color_hex(*display[source_channel].color);
  };
  for (size_t c = s.channels.size(); c < n; ++c) {
    ChannelSettings ch = s.channels[0];
    ch.colormap = file_color(c).value_or(n > 1 ? hues[c] : ch.colormap);
    ch.color_points.clear();
    s.channels.push_back(ch);
  }
  if (s.channels.size() > n) s.channels.resize(n);
  // Channel 0's colour is the default's when neither --colormap nor a settings file chose it
  // (a settings file that leaves it at RenderSettings' "gray" did not choose it either).
  const bool colour0_unchosen =
      !choice.colormap_given && (choice.defaults || (s.channels[0].colormap == "gray" && s.channels[0].color_points.empty()));
  if (colour0_unchosen && file_color(0)) {
    s.channels[0].colormap = *file_color(0);
    s.channels[0].color_points.clear();
  } else if (n > 1 && !choice.colormap_given && (choice.defaults || s.channels[0].colormap == "gray")) {
    s.channels[0].colormap = hues[0];
  }
  for (size_t c = 0; c < n && !choice.window_given; ++c) {
    VXR_ASSIGN_OR_RETURN(const auto w, auto_window(out.channels[c]));
    s.channels[c].window_lo = w.first;
    s.channels[c].window_hi = w.second;
  }
  if (s.iso_value == RenderSettings{}.iso_value && !choice.window_given && !choice.iso_given)
    s.iso_value = 0.5 * (s.channels[0].window_lo + s.channels[0].window_hi);
  VXR_RETURN_IF_ERROR(validate_render_settings(s, static_cast<uint32_t>(n)));
  out.settings = std::move(s);
  return out;
}

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

Result<VolumeSession> open_volume_session(const std::string& given, const SessionFlags& given_flags,
                                          SessionStep* failed_at) {
  SessionStep step_unused;
  SessionStep& step = failed_at ? *failed_at : step_unused;
  step = SessionStep::kSettings;
  // Flags and settings first: a bad one is reported before any file is read.
  VXR_ASSIGN_OR_RETURN(const SessionFlags flags, complete_session_flags(given_flags));
  VXR_ASSIGN_OR_RETURN(SettingsChoice choice, choose_settings(flags));
  VXR_ASSIGN_OR_RETURN(const auto voxel_size, parse_voxel_size_flag(flags.voxel_size));
  step = SessionStep::kSource;
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
  if (input.empty()) {
    VXR_ASSIGN_OR_RETURN(DenseVolume v, assets::sample_volume());
    std::vector<DenseVolume> channels;
    channels.push_back(std::move(v));
    VXR_ASSIGN_OR_RETURN(out.source, DenseChunkSource::create(std::move(channels)));
    out.description = "the bundled sample";
    if (choice.defaults) choice.window_given = true;  // the defaults were chosen for it
  } else if (input.rfind("procedural:", 0) == 0) {
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<ProceduralSource> p, open_procedural(input));
    out.source = std::move(p);
    out.description = input;
    if (!choice.window_given) {  // `vxr bench lod`'s: above the background noise (0..6)
      choice.settings.channels[0].window_lo = 8;
      choice.settings.channels[0].window_hi = 200;
      choice.window_given = true;
    }
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
    VXR_ASSIGN_OR_RETURN(std::shared_ptr<DenseChunkSource> dense, DenseChunkSource::create_series(std::move(series)));
    VXR_RETURN_IF_ERROR(dense->set_channel_display(std::move(loaded.channel_display)));
    out.source = std::move(dense);
  }
  if (voxel_size) out.source = with_voxel_size(out.source, *voxel_size);
  const VolumeInfo& info = out.source->info();
  out.description += " (" + dims_text(info) + ", " + std::to_string(out.source->levels().size()) + " levels)";
  step = SessionStep::kChannels;
  // Windows from a level small enough to read whole (~2 M voxels).
  const ChunkSource& src = *out.source;
  const uint32_t window_level = finest_level_that_fits(src, 4096, uint64_t(2) << 20);
  const AutoWindow auto_window = [&](uint32_t channel) -> Result<std::pair<double, double>> {
    VXR_ASSIGN_OR_RETURN(DenseVolume dense, read_level_dense(src, window_level, channel, flags.timepoint, uint64_t(64) << 20));
    return percentile_window(dense);
  };
  VXR_ASSIGN_OR_RETURN(DrawnSettings drawn, resolve_drawn_settings(std::move(choice), flags, given.empty() ? "the sample" : given,
                                                                   info.channels, info.timepoints, auto_window,
                                                                   info.channel_display));
  out.settings = std::move(drawn.settings);
  out.channels = std::move(drawn.channels);
  out.timepoint = flags.timepoint;
  for (std::string& n : drawn.notes) out.notes.push_back(std::move(n));
  return out;
}

}  // namespace vxr

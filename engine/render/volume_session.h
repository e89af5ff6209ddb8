// "The session from an input + flags": what a viewer draws, built the same
// way for every front end (vxr view: OpenXR, desktop, headless; vxr render
// can use it too). The input picks the ChunkSource the out-of-core renderer
// streams from; the flags override the defaults of the RenderSettings.
//
//   input                              source
//   ""                                 the bundled sample (MRI head), in memory
//   procedural:vessels:SIDE[:SEED]     synthetic vessels, generated per chunk
//   *.vxc, OME-Zarr                    read in place, chunk by chunk (open_chunk_source)
//   anything vxr imports               read whole (averaged down to fit the
//                                      memory limit), pyramid built in memory
//   NAME.vxr/ (a project folder)       its volume, and its annotation store drawn
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include "core/status.h"
#include "scene/render_settings.h"
#include "volume/chunk_source.h"
#include "volume/dense_volume.h"
#include "volume/procedural_source.h"

namespace vxr {

// The settings a session starts from instead of the defaults: a --settings
// file (plain RenderSettings, or a Scene) or a card's Scene.
struct SettingsStart {
  Scene scene;              // `render` always; a Scene's camera, volume, channels, timepoint too
  bool is_scene = false;    // a Scene: its channels, timepoint, voxel size and annotations are choices too
  bool has_window = false;  // windows given (a card's are resolved): no window from the data
};

// --settings FILE: a Scene when it has a "render", "camera" or "volume"
// section, else RenderSettings. Errors name the file (kNotFound, kInvalidArgument).
Result<SettingsStart> read_settings_file(const std::string& path);

struct SessionFlags {
  std::string colormap;   // empty: the default ("hot" for 8-bit data of unknown content)
  std::string window;     // "LO,HI" in data units; empty: from the data (percentiles) or the source's default
  std::string model;      // optical model name; empty: emission-absorption
  double step = 0.0;      // voxels per sample; 0: the default (0.5)
  std::string iso;        // "V": the isosurface at V (data units), and --model iso unless --model says otherwise; empty: the settings'
  // Shared by vxr view and vxr render (parse_volume_flags, apply_opacity_flags):
  std::string voxel_size;             // "X,Y,Z" world units per voxel, overriding the file's; empty: the file's
  std::string opacity;                // "LO:A,HI:B" opacity ramp over the window (fractions 0..1); empty: none
  std::string opacity_unit_distance;  // "D": opacity per D world units; "0": per voxel; empty: the settings'
  uint64_t max_dense_bytes = uint64_t(1) << 30;  // imported files: per channel, averaged down past it
  // An annotation store (engine/annotate) drawn with the volume; empty: a
  // project folder's own store (NAME.vxr/annotations), else none.
  std::string annotations;
  std::string channel;           // "2" or "0,2": the source channels drawn; empty: the first (up to 4)
  uint32_t timepoint = 0;        // the timepoint drawn (checked against the input's count)
  bool timepoint_given = false;  // false: a Scene's (--settings, card) timepoint, if any
  std::string settings;          // --settings FILE: RenderSettings or Scene JSON; the flags above override it
  // What a settings file (or a card) gave; complete_session_flags() reads `settings` into it.
  std::optional<SettingsStart> start;
};

struct VolumeSession {
  std::shared_ptr<const ChunkSource> source;
  RenderSettings settings;
  std::string description;         // "procedural:vessels:65536 (u8 65536x65536x65536, 11 levels)"
  std::vector<std::string> notes;  // worth telling the user (averaged down, channel 0 of 3)
  std::string annotation_store;    // the store to draw (SessionFlags::annotations or the project's); empty: none
  std::vector<uint32_t> channels;  // the source channels drawn, in the order of settings.channels
  uint32_t timepoint = 0;          // the timepoint drawn
};

// The settings chosen before any volume is read: the start's (--settings or a
// card) or the defaults, with --model --colormap --window --step --opacity
// --opacity-unit-distance applied and checked.
struct SettingsChoice {
  RenderSettings settings;
  bool window_given = false;    // by --window, the file or the card: no window from the data
  bool colormap_given = false;  // by --colormap
  bool iso_given = false;       // by --iso: no iso value from the window
  bool defaults = true;         // no file or card: a colour per channel when there are several
};
Result<SettingsChoice> choose_settings(const SessionFlags& flags);

// `flags` with what its start (read from --settings here) chose and the flags
// did not: a Scene's channels, timepoint, voxel size and annotation store.
Result<SessionFlags> complete_session_flags(SessionFlags flags);

// The settings for the channels drawn: --channel (default: the first up to
// 4, noted when there are more), --timepoint checked, then each drawn channel
// without settings gets its own (a copy of channel 0's with a distinct colour
// per channel) and, unless given, its window from `auto_window(source
// channel)` at the drawn timepoint. A channel whose colour is the default's
// choice (no --colormap for it, not set by --settings or a card; a settings
// file's "gray", RenderSettings' own default, counts as unset, as it does
// for the generated hues) takes the file's colour when `display` (the
// source's VolumeInfo::channel_display, indexed by source channel) states
// one: the single hue "#rrggbb".
struct DrawnSettings {
  RenderSettings settings;
  std::vector<uint32_t> channels;
  std::vector<std::string> notes;
};
using AutoWindow = std::function<Result<std::pair<double, double>>(uint32_t channel)>;
Result<DrawnSettings> resolve_drawn_settings(SettingsChoice choice, const SessionFlags& flags, const std::string& input,
                                             uint32_t volume_channels, uint32_t timepoints, const AutoWindow& auto_window,
                                             const std::vector<ChannelDisplay>& display = {});

// --channel "2" or "0,2": at most VXR_MAX_CHANNELS channels of `input`'s, each once.
Result<std::vector<uint32_t>> parse_channel_flag(const std::string& text, const std::string& input,
                                                 uint32_t volume_channels);

// --timepoint T against the input's count: kInvalidArgument naming both.
Status check_timepoint(const std::string& input, uint32_t timepoint, uint32_t timepoints);

// The RenderSettings a viewer starts from for 8-bit data of unknown content.
RenderSettings default_view_settings();

// --voxel-size: three finite numbers > 0, or nullopt when the flag is empty.
Result<std::optional<std::array<double, 3>>> parse_voxel_size_flag(const std::string& text);

// The --voxel-size text of `v`, exact (17 significant digits), e.g. for a card's voxel size.
std::string voxel_size_text(const std::array<double, 3>& v);

// --opacity LO:A,HI:B (LO < HI window fractions in 0..1, A and B opacities in
// 0..1): every channel's opacity is 0 below LO, rises linearly from A at LO
// to B at HI and stays B above. --opacity-unit-distance D (>= 0, finite).
// Errors name the flag and what is wrong.
Status apply_opacity_flags(const SessionFlags& f, RenderSettings& s);

// `source` seen with level-0 voxel size `voxel_size` (world units per voxel):
// every other property and every chunk unchanged.
std::shared_ptr<const ChunkSource> with_voxel_size(std::shared_ptr<const ChunkSource> source,
                                                   const std::array<double, 3>& voxel_size);

// --voxel-size on volumes read whole: each channel's voxel size becomes the
// flag's, times what averaging down by `shrink` made of it (axes longer
// than one voxel). Nothing when the flag is empty.
Status apply_voxel_size_flag(const SessionFlags& f, uint32_t shrink, std::vector<DenseVolume>& channels);

// Where open_volume_session failed: the flags or settings (a usage error),
// opening the input, or choosing channels, timepoint and windows on it.
enum class SessionStep { kSettings, kSource, kChannels };

// The session vxr view and vxr render draw: complete_session_flags,
// choose_settings, the source, then resolve_drawn_settings with windows from a
// level of the source small enough to read whole.
Result<VolumeSession> open_volume_session(const std::string& input, const SessionFlags& flags,
                                          SessionStep* failed_at = nullptr);

// `procedural:vessels:SIDE[:SEED]`: the synthetic vessel volume of `vxr bench
// lod`, SIDE^3 voxels (up to 131072), generated on demand.
Result<std::unique_ptr<ProceduralSource>> open_procedural(const std::string& spec);

// Values at the 0.5 and 99.5 percentiles of a volume (sampled), in data units:
// the default window of vxr view and vxr render.
std::pair<double, double> percentile_window(const DenseVolume& v);

}  // namespace vxr

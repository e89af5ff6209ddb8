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

#include <memory>
#include <utility>
#include <string>
#include <vector>

#include "core/status.h"
#include "scene/render_settings.h"
#include "volume/chunk_source.h"
#include "volume/dense_volume.h"
#include "volume/procedural_source.h"

namespace vxr {

struct SessionFlags {
  std::string colormap;   // empty: the default ("hot" for 8-bit data of unknown content)
  std::string window;     // "LO,HI" in data units; empty: from the data (percentiles) or the source's default
  std::string model;      // optical model name; empty: emission-absorption
  double step = 0.0;      // voxels per sample; 0: the default (0.5)
  uint64_t max_dense_bytes = uint64_t(1) << 30;  // imported files: per channel, averaged down past it
  // An annotation store (engine/annotate) drawn with the volume; empty: a
  // project folder's own store (NAME.vxr/annotations), else none.
  std::string annotations;
};

struct VolumeSession {
  std::shared_ptr<const ChunkSource> source;
  RenderSettings settings;
  std::string description;         // "procedural:vessels:65536 (u8 65536x65536x65536, 11 levels)"
  std::vector<std::string> notes;  // worth telling the user (averaged down, channel 0 of 3)
  std::string annotation_store;    // the store to draw (SessionFlags::annotations or the project's); empty: none
};

// The RenderSettings a viewer starts from for 8-bit data of unknown content.
RenderSettings default_view_settings();

Result<VolumeSession> open_volume_session(const std::string& input, const SessionFlags& flags);

// `procedural:vessels:SIDE[:SEED]`: the synthetic vessel volume of `vxr bench
// lod`, SIDE^3 voxels (up to 131072), generated on demand.
Result<std::unique_ptr<ProceduralSource>> open_procedural(const std::string& spec);

// Values at the 0.5 and 99.5 percentiles of a volume (sampled), in data units:
// the default window of vxr view and vxr render.
std::pair<double, double> percentile_window(const DenseVolume& v);

}  // namespace vxr

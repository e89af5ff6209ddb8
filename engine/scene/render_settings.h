// The plain, serialisable render state: what `vxr render --settings` reads and
// what cards store. No behaviour here: the renderer (engine/render) checks and
// uses it; the JSON round-trip is lossless.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace vxr {

enum class OpticalModel { kEmissionAbsorption, kEmission, kMip, kMinIp, kAverage, kIsosurface };
enum class ChannelBlend { kAdditive, kComposite };
enum class DepthColorMode { kOff, kView, kAxisX, kAxisY, kAxisZ };

// JSON/CLI names: "ea", "emission", "mip", "minip", "average", "iso".
const char* optical_model_name(OpticalModel m);
bool optical_model_from_name(const std::string& name, OpticalModel* out);

struct ColorPoint {
  double x = 0.0;                        // window-normalised position 0..1
  std::array<double, 3> rgb{0, 0, 0};    // 0..1
  bool operator==(const ColorPoint&) const = default;
};
struct OpacityPoint {
  double x = 0.0;        // window-normalised position 0..1
  double opacity = 0.0;  // 0..1, scales the extinction `density`
  bool operator==(const OpacityPoint&) const = default;
};

// One channel's transfer function. Values are windowed (lo..hi in the data's
// own units -> 0..1), raised to `gamma`, then looked up: colour from
// `color_points` when given, else from `colormap`; opacity from
// `opacity_points` when given, else equal to the normalised value.
struct ChannelSettings {
  bool enabled = true;
  double window_lo = 0.0;
  double window_hi = 255.0;
  double gamma = 1.0;
  std::string colormap = "gray";
  std::vector<ColorPoint> color_points;
  std::vector<OpacityPoint> opacity_points;
  bool operator==(const ChannelSettings&) const = default;
};

struct ShadingSettings {  // isosurface shading (headlight)
  double ambient = 0.25;
  double diffuse = 0.75;
  double specular = 0.25;
  double shininess = 24.0;
  bool operator==(const ShadingSettings&) const = default;
};

struct GradientOpacity {  // opacity *= ramp(|grad|) with |grad| in window units per voxel
  bool enabled = false;
  double lo = 0.0;
  double hi = 0.1;
  bool operator==(const GradientOpacity&) const = default;
};

// Clipping in volume fractions (0..1 along each axis of the whole volume, so
// the same numbers mean the same cut at any size or pyramid level): a plane
// keeping the points f with dot(cut_normal, f) + cut_offset >= 0, and a box
// keeping [roi_lo, roi_hi]. The out-of-core renderer's LodSettings cut/roi
// take them in level-0 voxels (render/lod/lod_traversal.h clip_for_volume).
struct ClipSettings {
  bool cut = false;
  std::array<double, 3> cut_normal{0, 0, 1};
  double cut_offset = 0.0;
  bool roi = false;
  std::array<double, 3> roi_lo{0, 0, 0}, roi_hi{1, 1, 1};
  bool operator==(const ClipSettings&) const = default;
};

struct RenderSettings {
  OpticalModel model = OpticalModel::kEmissionAbsorption;
  std::vector<ChannelSettings> channels{ChannelSettings{}};  // one per volume channel (up to 4)
  ChannelBlend blend = ChannelBlend::kAdditive;
  double step_voxels = 0.5;            // distance between samples, in voxels
  double density = 0.25;               // extinction per length unit at opacity 1 (see below)
  // The length unit of `density`. 0 (default, older files): one voxel along
  // the ray, whatever the voxel's physical size. D > 0: D world units (the
  // volume's physical voxel size), like VTK's scalar opacity unit distance, so
  // a voxel twice as thick in z absorbs twice as much along z and
  // anisotropic data renders like the same data resampled isotropically.
  double opacity_unit_distance = 0.0;
  double early_termination = 1.0 / 512.0;  // stop a ray once its transmittance is <= this
  // Exact opacity from extinction, 1 - exp(-tau * step) (true), or the naive
  // linear correction a = tau * step clamped to 1 (false). The naive form exists
  // to measure what the exact one buys (vxr bench accuracy); the CPU reference
  // always integrates exactly.
  bool opacity_correction = true;
  bool jitter = false;                 // deterministic per-pixel offset of the sample positions
  // Where each sample sits inside its segment when not jittered: 0.5, the
  // midpoint, converges at second order; 0, the segment start, is the classic
  // first-order scheme.
  double sample_offset = 0.5;
  double iso_value = 128.0;            // isosurface threshold, data units of channel `iso_channel`
  uint32_t iso_channel = 0;
  ShadingSettings shading;
  DepthColorMode depth_color = DepthColorMode::kOff;  // colour by depth through each channel's colour map
  GradientOpacity gradient_opacity;
  uint32_t max_steps = 1u << 16;
  ClipSettings clip;  // JSON "clip" (written only when a plane or box is on)
  bool operator==(const RenderSettings&) const = default;
};

struct CameraState {
  std::array<double, 3> eye{0, 0, 1};
  std::array<double, 3> target{0, 0, 0};
  std::array<double, 3> up{0, 1, 0};
  double fov_y_deg = 40.0;
  bool operator==(const CameraState&) const = default;
};

// Where the volume sits in the world (the paper's grab/pinch transform):
// world = position + rotation * (scale * v) for a point v of the volume's own
// frame (world units, volume centred at 0, as CameraState). Uniform scale only:
// the two-hand pinch scales about a point, and a uniform scale keeps the
// picture a camera move away (see camera_in_volume_frame).
struct VolumeTransform {
  std::array<double, 3> position{0, 0, 0};
  std::array<double, 4> rotation{1, 0, 0, 0};  // quaternion w, x, y, z (normalised on use)
  double scale = 1.0;
  bool operator==(const VolumeTransform&) const = default;
};

// What a card stores: everything `vxr render --card` needs to draw the same
// picture again. Fields left at their defaults mean "the viewer's choice".
struct Scene {
  std::string volume;  // the input: an absolute path, an OME-Zarr folder or procedural:vessels:SIDE
  uint32_t timepoint = 0;
  std::vector<uint32_t> channels;  // the volume's channels drawn, in order; empty: the first (up to 4)
  VolumeTransform transform;
  CameraState camera;  // the user's pose (eye, target, up) in world units
  bool has_camera = false;  // false: the viewer picks a default view
  std::array<uint32_t, 2> viewport{0, 0};  // image width, height in pixels; 0: the viewer's size
  // What drew a card's snapshot: "lod" (the one renderer), or "dense"/"compute"/
  // "fragment" in cards made before the dense ray caster was removed (such a
  // card is drawn out of core now). Kept so old cards still read.
  std::string renderer;
  std::string path;
  double lod_bias = 0.0;  // lod renderer: log2 voxels per pixel accepted
  std::string annotations;  // annotation store drawn with the volume (absolute path); "": none or the project's
  RenderSettings render;
  // World units per voxel replacing the input's own (--voxel-size); all 0: the input's.
  std::array<double, 3> voxel_size{0, 0, 0};
  bool operator==(const Scene&) const = default;
};

// The camera that, looking at the untransformed volume, sees what `camera`
// sees of the volume placed by `t`: the inverse transform applied to the
// eye, target and up (fov unchanged). Exact in double.
CameraState camera_in_volume_frame(const CameraState& camera, const VolumeTransform& t);

// JSON text <-> structs. Missing keys keep their defaults; unknown keys are
// ignored; wrong types, unknown enum names and malformed JSON give
// kInvalidArgument naming the key.
std::string render_settings_to_json(const RenderSettings& s);
Result<RenderSettings> render_settings_from_json(const std::string& text);
std::string scene_to_json(const Scene& s);
Result<Scene> scene_from_json(const std::string& text);

}  // namespace vxr

// The annotation types a project stores (engine/annotate/annotation_store.h):
// plain structs, no behaviour beyond small geometric helpers. Positions are in
// volume coordinates (voxels of the finest level, x y z, continuous), so they
// stay valid when the voxel size is corrected later; metric figures come from
// VoxelSpace.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vxr::annotate {

using Vec3 = std::array<double, 3>;
using Id = uint64_t;  // unique per kind within a store; 0 is never used

// Voxel size and its unit: turns volume coordinates into lengths.
struct VoxelSpace {
  Vec3 voxel_size{1.0, 1.0, 1.0};
  std::string unit = "um";
  // Physical position of a volume-coordinate point (component-wise scale).
  Vec3 to_physical(const Vec3& p) const;
  Vec3 from_physical(const Vec3& p) const;
  // Metric distance between two volume-coordinate points; anisotropic voxels
  // scale each axis before the norm.
  double distance(const Vec3& a, const Vec3& b) const;
  bool operator==(const VoxelSpace&) const = default;
};

// Micrometres per `unit` ("um", "µm", "micron", "micrometer", "nm", "mm"); 0 when unknown.
double micrometres_per_unit(const std::string& unit);

// One counted object / placed ball (counting tool, feature tracking).
struct Marker {
  Id id = 0;
  std::string cls = "default";              // counting class
  std::array<double, 4> color{1, 1, 0, 1};  // RGBA 0..1
  Vec3 pos{0, 0, 0};
  uint32_t timepoint = 0;
  bool operator==(const Marker&) const = default;
};

// Two points; the length is derived (VoxelSpace::distance), never stored.
struct Measurement {
  Id id = 0;
  std::string label;
  Vec3 a{0, 0, 0};
  Vec3 b{0, 0, 0};
  uint32_t timepoint = 0;
  bool operator==(const Measurement&) const = default;
};

// A skeleton node. `parent` is kNoParent for a root; a skeleton may have
// several roots (a forest), as SWC files do.
constexpr int64_t kNoParent = -1;
struct SkeletonNode {
  int64_t id = 0;  // > 0, unique within its skeleton
  Vec3 pos{0, 0, 0};
  double radius = 0.0;  // in VoxelSpace::unit (SWC radii are lengths, not voxels)
  int type = 0;         // SWC structure type: 1 soma, 2 axon, 3 basal, 4 apical, ...
  int64_t parent = kNoParent;
  bool operator==(const SkeletonNode&) const = default;
};

// A feature followed through time: markers, at most one per timepoint,
// kept in timepoint order.
struct Track {
  Id id = 0;
  std::string name;
  std::vector<Id> markers;
  bool operator==(const Track&) const = default;
};

// Axis-aligned box in volume coordinates, min <= max on every axis.
struct Roi {
  Id id = 0;
  std::string name;
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
  bool contains(const Vec3& p) const;
  bool operator==(const Roi&) const = default;
};

// A segmented surface (one part of an imported OBJ: a tissue, a cell, a
// substructure). The triangles live beside it in the store; `parent` makes
// the hierarchy (0: top level).
struct StoredMesh {
  Id id = 0;
  std::string name;
  Id parent = 0;
  std::array<double, 4> color{0.8, 0.8, 0.8, 1.0};
  uint64_t vertices = 0, triangles = 0;
  bool operator==(const StoredMesh&) const = default;
};

// A saved finding: the Scene to restore, a note, and optional media.
struct Card {
  Id id = 0;
  std::string title;
  std::string note;
  std::string scene_json;             // scene_to_json() text (engine/scene/render_settings.h)
  int64_t created_unix = 0;           // seconds since 1970, UTC
  std::string snapshot_path;          // a PNG kept outside the store (optional)
  std::vector<uint8_t> snapshot_png;  // PNG bytes kept in the store (optional)
  std::vector<uint8_t> audio_wav;     // WAV voice memo (optional)
  bool operator==(const Card&) const = default;
};

}  // namespace vxr::annotate

// Volumes, cameras and settings shared by the ray-caster tests.
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "assets/assets.h"
#include "render/camera.h"
#include "scene/render_settings.h"
#include "volume/dense_volume.h"

namespace vxr::test {

// The bundled MRI head (186x226x27 u8, voxel 1x1x5): the same bytes as
// ../shared/testdata/slices/mri-stack/*.tif.
inline DenseVolume mri() {
  auto v = assets::sample_volume();
  REQUIRE(v.is_ok());
  return std::move(v).value();
}

inline DenseVolume to_u16(const DenseVolume& v8) {
  DenseVolume v = v8;
  v.dtype = DType::kU16;
  v.data.resize(v8.voxel_count() * 2);
  for (uint64_t i = 0; i < v8.voxel_count(); ++i) {
    const uint16_t x = static_cast<uint16_t>(v8.data[i] * 257);
    std::memcpy(&v.data[i * 2], &x, 2);
  }
  return v;
}

inline DenseVolume to_f32(const DenseVolume& v8, double scale, double offset) {
  DenseVolume v = v8;
  v.dtype = DType::kF32;
  v.data.resize(v8.voxel_count() * 4);
  for (uint64_t i = 0; i < v8.voxel_count(); ++i) {
    const float x = static_cast<float>(v8.data[i] * scale + offset);
    std::memcpy(&v.data[i * 4], &x, 4);
  }
  return v;
}

// Four u8 channels of n^3 voxels, each a soft ball at a different place: the
// picture shows which channel went where.
inline std::vector<DenseVolume> four_balls(uint32_t n = 48) {
  const double centres[4][3] = {{0.35, 0.35, 0.5}, {0.65, 0.35, 0.5}, {0.35, 0.65, 0.5}, {0.65, 0.65, 0.5}};
  std::vector<DenseVolume> out(4);
  for (int c = 0; c < 4; ++c) {
    DenseVolume& v = out[c];
    v.dims = {n, n, n};
    v.data.resize(v.voxel_count());
    size_t i = 0;
    for (uint32_t z = 0; z < n; ++z)
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x) {
          const double dx = (x + 0.5) / n - centres[c][0], dy = (y + 0.5) / n - centres[c][1],
                       dz = (z + 0.5) / n - centres[c][2];
          const double r = std::sqrt(dx * dx + dy * dy + dz * dz) / 0.22;
          v.data[i++] = static_cast<uint8_t>(std::lround(255.0 * std::clamp(1.0 - r, 0.0, 1.0)));
        }
  }
  return out;
}

inline Camera mri_camera(const DenseVolume& v) { return orbit_camera({v.dims, v.voxel_size}, 30.0, 25.0, 1.25); }

// Window 20..220 of the head's u8 values, extinction 0.08 per voxel.
inline RenderSettings mri_settings(OpticalModel model, const char* colormap = "gray") {
  RenderSettings s;
  s.model = model;
  s.channels[0].colormap = colormap;
  s.channels[0].window_lo = 20;
  s.channels[0].window_hi = 220;
  s.step_voxels = 0.25;
  s.density = 0.08;
  s.iso_value = 60;
  return s;
}

}  // namespace vxr::test

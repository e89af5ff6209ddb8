#include "volume/synthetic_microscopy.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

namespace vxr {
namespace {

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Approximately standard normal from one 64-bit hash: the sum of four 16-bit
// uniforms (Irwin-Hall), scaled to unit variance.
float gaussian_of(uint64_t h) {
  const uint32_t s = uint32_t(h & 0xffff) + uint32_t((h >> 16) & 0xffff) + uint32_t((h >> 32) & 0xffff) + uint32_t(h >> 48);
  return (float(s) * (1.0f / 65536.0f) - 2.0f) * 1.7320508f;
}

}  // namespace

SyntheticMicroscopySource::SyntheticMicroscopySource(const std::array<uint64_t, 3>& dims, uint64_t seed) : seed_(seed) {
  info_.dims = dims;
  info_.dtype = DType::kU16;
  info_.unit = "um";
  info_.voxel_size = {0.5, 0.5, 1.0};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const uint64_t count = std::max<uint64_t>(8, info_.voxels_per_volume() / 400000);
  blobs_.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    Blob b;
    b.x = u(rng) * double(dims[0]);
    b.y = u(rng) * double(dims[1]);
    b.z = u(rng) * double(dims[2]);
    b.r = 2.0 + 22.0 * u(rng) * u(rng);  // many small cells, a few large ones
    b.amp = 300.0 + 3700.0 * u(rng);
    blobs_.push_back(b);
  }
}

Status SyntheticMicroscopySource::read_region(uint32_t, uint32_t, const Box3& box, std::span<uint8_t> dst) {
  if (dst.size() != box.voxels() * 2) return invalid_argument("synthetic source: destination has the wrong size");
  const uint64_t nx = box.size[0], ny = box.size[1];
  const double kCut = 2.5;  // blobs end at 2.5 sigma
  std::vector<float> plane(nx * ny), sx(nx), sy(ny), ex, ey;
  for (uint64_t i = 0; i < nx; ++i) sx[i] = float(0.5 + 0.5 * std::sin(double(box.origin[0] + i) * 0.011));
  for (uint64_t j = 0; j < ny; ++j) sy[j] = float(0.5 + 0.5 * std::sin(double(box.origin[1] + j) * 0.017 + 1.0));
  for (uint64_t k = 0; k < box.size[2]; ++k) {
    const uint64_t z = box.origin[2] + k;
    // Background: camera offset plus a smooth autofluorescence haze.
    const float sz = float(0.5 + 0.5 * std::sin(double(z) * 0.007 + 2.0));
    for (uint64_t j = 0; j < ny; ++j)
      for (uint64_t i = 0; i < nx; ++i) plane[j * nx + i] = 100.0f + 60.0f * sx[i] * sy[j] * sz;
    // Cells: separable Gaussians over each blob's footprint in this plane.
    for (const Blob& b : blobs_) {
      const double dz = double(z) - b.z, reach = kCut * b.r;
      if (std::abs(dz) >= reach) continue;
      const double x0 = std::max<double>(double(box.origin[0]), std::ceil(b.x - reach));
      const double x1 = std::min<double>(double(box.origin[0] + nx), std::floor(b.x + reach) + 1);
      const double y0 = std::max<double>(double(box.origin[1]), std::ceil(b.y - reach));
      const double y1 = std::min<double>(double(box.origin[1] + ny), std::floor(b.y + reach) + 1);
      if (x0 >= x1 || y0 >= y1) continue;
      const double inv = 1.0 / (2.0 * b.r * b.r);
      const float a = float(b.amp * std::exp(-dz * dz * inv));
      ex.resize(size_t(x1 - x0));
      ey.resize(size_t(y1 - y0));
      for (size_t i = 0; i < ex.size(); ++i) {
        const double d = x0 + double(i) - b.x;
        ex[i] = float(std::exp(-d * d * inv));
      }
      for (size_t j = 0; j < ey.size(); ++j) {
        const double d = y0 + double(j) - b.y;
        ey[j] = a * float(std::exp(-d * d * inv));
      }
      const uint64_t ox = uint64_t(x0) - box.origin[0], oy = uint64_t(y0) - box.origin[1];
      for (size_t j = 0; j < ey.size(); ++j) {
        float* row = plane.data() + (oy + j) * nx + ox;
        for (size_t i = 0; i < ex.size(); ++i) row[i] += ey[j] * ex[i];
      }
    }
    // Shot noise, hashed from the voxel's coordinates so every read agrees.
    uint8_t* out = dst.data() + k * nx * ny * 2;
    for (uint64_t j = 0; j < ny; ++j) {
      const uint64_t y = box.origin[1] + j;
      const uint64_t row_key = splitmix64(seed_ ^ (z * 0x100000001b3ull + y) * 0x9e3779b97f4a7c15ull);
      for (uint64_t i = 0; i < nx; ++i) {
        const float s = plane[j * nx + i];
        const float v = s + std::sqrt(s) * gaussian_of(splitmix64(row_key + box.origin[0] + i));
        const uint16_t q = uint16_t(std::clamp(v + 0.5f, 0.0f, 65535.0f));
        std::memcpy(out + (j * nx + i) * 2, &q, 2);
      }
    }
  }
  return Status::ok();
}

}  // namespace vxr

#include "bench/stability.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <span>

#include "render/colormap.h"
#include "render/lod/memory_volume.h"
#include "render/reference_renderer.h"

namespace vxr::bench {
namespace {

// The bound every ordinary class shares, in 0..1 output units. GPU and
// reference sample at the same positions; what differs is float32 ray setup
// and lavapipe's 8-bit trilinear weights on UNORM textures (up to 2/255 in the
// sampled value, ../shared/design/lavapipe.md), which a transfer function with
// density up to 4 per voxel can amplify a little.
constexpr double kBase = 4.0 / 255.0;

enum Cls : uint32_t {
  kAxisParallel,
  kGrazing,
  kEyeOnFace,
  kEyeOnEdge,
  kEyeOnCorner,
  kEyeInside,
  kZeroSize,
  kThin,
  kOffset,
  kScale,
  kAnisotropy,
  kNanInf,
  kAllZero,
  kAllMax,
  kExtremeTf,
  kFineStep,
  kCoarseStep,
  kClassCount
};

}  // namespace

const std::vector<StabilityClass>& stability_classes() {
  static const std::vector<StabilityClass> classes = {
      {"axis_parallel", kBase, "rays exactly along an axis: the slab test must not make NaN; same samples as the reference"},
      {"grazing", kBase, "rays in or within 1e-7..1e-3 rad of a face plane: hit/miss must agree with the reference"},
      {"eye_on_face", kBase, "eye exactly on a face plane of the box"},
      {"eye_on_edge", kBase, "eye exactly on an edge of the box"},
      {"eye_on_corner", kBase, "eye exactly on a corner of the box"},
      {"eye_inside", kBase, "eye inside the volume, rays start at t = 0"},
      {"zero_size", 0.0, "a zero side: both renderers must refuse with a clear error, nothing is drawn"},
      {"one_voxel_thick", kBase, "1-voxel-thick slabs and rods: clamp-to-edge filtering across the whole volume"},
      {"huge_offset", kBase, "box centre 2^10..2^24 voxels from the world origin: composed in double, so as at the origin"},
      {"extreme_scale", kBase, "voxel sizes 1e-6..1e6 world units: voxel-space rays are scale-free"},
      {"anisotropy", kBase, "voxel aspect up to 1:100: rays mapped linearly into voxel space"},
      {"nan_inf", kBase, "float data with NaN and +-Inf voxels: read as 0 and +-1e30 by both renderers"},
      {"all_zero", kBase, "constant zero data"},
      {"all_max", kBase, "constant maximum data (255, 65535, FLT_MAX)"},
      {"extreme_tf", kBase,
       "density 1e-6..1e4 per voxel, narrow/wide windows, gamma 0.01..100, step opacity ramps, termination 0..1e-2"},
      {"fine_step", kBase, "steps 1/64..1/8 voxel: thousands of samples per ray, positions from the step index"},
      {"coarse_step", kBase, "steps 2..8 voxels: few samples, partial last segment"},
  };
  return classes;
}

namespace {

using glm::dvec3;

struct Rng {
  std::mt19937_64 g;
  explicit Rng(uint64_t seed) : g(seed) {}
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }
  double log_uni(double a, double b) { return std::exp(uni(std::log(a), std::log(b))); }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(g); }
  bool chance(double p) { return uni(0.0, 1.0) < p; }
  template <typename T>
  const T& pick(const std::vector<T>& v) { return v[static_cast<size_t>(integer(0, int(v.size()) - 1))]; }
};

dvec3 dims_of(const DenseVolume& v) { return {double(v.dims[0]), double(v.dims[1]), double(v.dims[2])}; }

// Voxel-space point/vector -> world, the inverse of VolumePlacement's mapping.
dvec3 voxel_to_world(const DenseVolume& v, const dvec3& p) {
  const dvec3 q = p - 0.5 * dims_of(v);
  return dvec3(v.origin[0], v.origin[1], v.origin[2]) +
         dvec3(q.x * v.voxel_size[0], q.y * v.voxel_size[1], q.z * v.voxel_size[2]);
}
dvec3 voxel_dir_to_world(const DenseVolume& v, const dvec3& d) {
  return {d.x * v.voxel_size[0], d.y * v.voxel_size[1], d.z * v.voxel_size[2]};
}

dvec3 random_unit(Rng& r) {
  for (;;) {
    const dvec3 d(r.uni(-1, 1), r.uni(-1, 1), r.uni(-1, 1));
    const double l = glm::length(d);
    if (l > 0.1 && l <= 1.0) return d / l;
  }
}

// A camera at voxel-space `eye` looking along voxel-space `dir`, in world space.
Camera look(const DenseVolume& v, const dvec3& eye, const dvec3& dir, Rng& r) {
  Camera c;
  c.eye = voxel_to_world(v, eye);
  const dvec3 wdir = glm::normalize(voxel_dir_to_world(v, dir));
  // The target one "world length" ahead keeps target - eye well conditioned at any scale.
  const double s = std::max({v.voxel_size[0], v.voxel_size[1], v.voxel_size[2]}) * 4.0;
  c.target = c.eye + wdir * s;
  const std::vector<dvec3> ups = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  c.up = r.pick(ups);
  if (std::abs(glm::dot(c.up, wdir)) > 0.999) c.up = dvec3(c.up.y, c.up.z, c.up.x);
  c.fov_y_deg = r.uni(5.0, 100.0);
  return c;
}

// A camera outside the box looking at a random point of it.
Camera outside_view(const DenseVolume& v, Rng& r) {
  const dvec3 d = dims_of(v);
  const dvec3 target = d * dvec3(r.uni(0.2, 0.8), r.uni(0.2, 0.8), r.uni(0.2, 0.8));
  const dvec3 eye = target + random_unit(r) * glm::length(d) * r.uni(0.8, 3.0);
  return look(v, eye, target - eye, r);
}

void fill(DenseVolume& v, Rng& r, int pattern) {
  const uint64_t n = v.voxel_count();
  v.data.assign(n * dtype_bytes(v.dtype), 0);
  const double maxv = v.dtype == DType::kU8 ? 255.0 : v.dtype == DType::kU16 ? 65535.0 : 1000.0;
  const dvec3 d = dims_of(v);
  const dvec3 c = d * dvec3(r.uni(0.3, 0.7), r.uni(0.3, 0.7), r.uni(0.3, 0.7));
  const double radius = std::max(1.0, glm::length(d) * r.uni(0.15, 0.5));
  uint64_t i = 0;
  for (uint32_t z = 0; z < v.dims[2]; ++z)
    for (uint32_t y = 0; y < v.dims[1]; ++y)
      for (uint32_t x = 0; x < v.dims[0]; ++x, ++i) {
        const dvec3 p(x + 0.5, y + 0.5, z + 0.5);
        double f = 0.0;  // 0..1
        switch (pattern) {
          case 0: f = r.uni(0.0, 1.0); break;                                        // noise
          case 1: f = std::exp(-glm::dot(p - c, p - c) / (radius * radius)); break;  // blob
          case 2: f = (x + y + z) / std::max(1.0, d.x + d.y + d.z - 3.0); break;    // ramp
          case 3: f = ((x ^ y ^ z) & 1) ? 1.0 : 0.0; break;                         // checker
          default: f = r.chance(0.1) ? 1.0 : 0.0; break;                             // sparse
        }
        const double value = f * maxv;
        switch (v.dtype) {
          case DType::kU8: v.data[i] = static_cast<uint8_t>(std::lround(value)); break;
          case DType::kU16: {
            const uint16_t s = static_cast<uint16_t>(std::lround(value));
            std::memcpy(&v.data[i * 2], &s, 2);
            break;
          }
          default: {
            const float s = static_cast<float>(value);
            std::memcpy(&v.data[i * 4], &s, 4);
            break;
          }
        }
      }
}

double dtype_max(DType t) { return t == DType::kU8 ? 255.0 : t == DType::kU16 ? 65535.0 : 1000.0; }

void random_settings(RenderSettings& s, const DenseVolume& v, Rng& r) {
  // Isosurfaces are left out: a first-hit test flips a whole pixel when float
  // and double straddle the threshold, which says nothing about stability.
  const std::vector<OpticalModel> models = {OpticalModel::kEmissionAbsorption, OpticalModel::kEmissionAbsorption,
                                            OpticalModel::kEmissionAbsorption, OpticalModel::kEmission,
                                            OpticalModel::kMip,                OpticalModel::kMinIp,
                                            OpticalModel::kAverage};
  s.model = r.pick(models);
  const double maxv = dtype_max(v.dtype);
  ChannelSettings& ch = s.channels[0];
  ch.window_lo = r.chance(0.5) ? 0.0 : r.uni(0.0, 0.4) * maxv;
  ch.window_hi = r.chance(0.5) ? maxv : ch.window_lo + r.uni(0.2, 1.0) * (maxv - ch.window_lo);
  const std::vector<std::string> maps = {"gray", "viridis", "magma", "turbo", "red"};
  ch.colormap = r.pick(maps);
  s.step_voxels = r.log_uni(0.125, 2.0);
  s.density = r.log_uni(0.02, 4.0);
  s.early_termination = r.chance(0.3) ? 0.0 : 1.0 / 512.0;
  s.max_steps = 1u << 20;
}

}  // namespace

StabilityCase make_stability_case(uint64_t seed, uint32_t index) {
  // splitmix64 of (seed, index) seeds the case's own generator.
  uint64_t z = seed + 0x9e3779b97f4a7c15ull * (uint64_t(index) + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  Rng r(z ^ (z >> 31));

  StabilityCase c;
  c.index = index;
  c.class_index = index % kClassCount;
  DenseVolume& v = c.volume;
  const std::vector<DType> types = {DType::kU8, DType::kU8, DType::kU16, DType::kF32};
  v.dtype = r.pick(types);
  for (int a = 0; a < 3; ++a) v.dims[a] = static_cast<uint32_t>(r.integer(2, 12));
  v.voxel_size = {1.0, 1.0, 1.0};
  const bool odd = r.chance(0.7);  // odd sizes put a pixel ray exactly on the view axis
  c.width = static_cast<uint32_t>(r.integer(4, 9) * 2 + (odd ? 1 : 0));
  c.height = static_cast<uint32_t>(r.integer(4, 9) * 2 + (odd ? 1 : 0));
  int pattern = r.integer(0, 4);

  const uint32_t cls = c.class_index;
  if (cls == kThin) {
    const int a = r.integer(0, 2);
    v.dims[a] = 1;
    if (r.chance(0.3)) v.dims[(a + 1) % 3] = 1;
  }
  if (cls == kScale) {
    const double s = r.log_uni(1e-6, 1e6);
    v.voxel_size = {s, s, s};
  }
  if (cls == kAnisotropy) {
    const double base = r.log_uni(0.01, 100.0);
    v.voxel_size = {base, base * r.log_uni(1.0, 100.0), base * r.log_uni(1.0, 100.0)};
    std::shuffle(v.voxel_size.begin(), v.voxel_size.end(), r.g);
    if (r.chance(0.5)) v.voxel_size[r.integer(0, 2)] = base * 100.0;  // the full 1:100
  }
  if (cls == kOffset) {
    const double s = r.log_uni(0.01, 10.0);
    v.voxel_size = {s, s * r.uni(1.0, 3.0), s};
    const dvec3 dir = random_unit(r);
    const double voxels = std::exp2(r.uni(10.0, 24.0));
    for (int a = 0; a < 3; ++a) v.origin[a] = dir[a] * voxels * v.voxel_size[a];
    if (r.chance(0.3))  // exactly 2^24 voxels along one axis
      v.origin = {std::exp2(24.0) * v.voxel_size[0], 0.0, 0.0};
  }
  if (cls == kNanInf) v.dtype = DType::kF32;
  if (cls == kAllZero || cls == kAllMax) pattern = -1;
  if (cls == kZeroSize) {
    v.dims[r.integer(0, 2)] = 0;
    c.expect_rejection = true;
  }

  fill(v, r, pattern < 0 ? 0 : pattern);
  if (pattern < 0) {  // constant data
    const uint64_t n = v.voxel_count();
    for (uint64_t i = 0; i < n; ++i) {
      if (v.dtype == DType::kU8) v.data[i] = cls == kAllMax ? 255 : 0;
      if (v.dtype == DType::kU16) {
        const uint16_t s = cls == kAllMax ? 65535 : 0;
        std::memcpy(&v.data[i * 2], &s, 2);
      }
      if (v.dtype == DType::kF32) {
        const float s = cls == kAllMax ? FLT_MAX : 0.0f;
        std::memcpy(&v.data[i * 4], &s, 4);
      }
    }
  }
  if (cls == kNanInf) {
    const float specials[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                              -std::numeric_limits<float>::infinity(), FLT_MAX, -FLT_MAX};
    const double fraction = r.uni(0.02, 0.5);
    for (uint64_t i = 0; i < v.voxel_count(); ++i)
      if (r.chance(fraction)) std::memcpy(&v.data[i * 4], &specials[r.integer(0, 4)], 4);
  }

  random_settings(c.settings, v, r);
  if (cls == kAllMax && v.dtype == DType::kF32) {
    c.settings.channels[0].window_lo = 0.0;
    c.settings.channels[0].window_hi = r.chance(0.5) ? 1000.0 : 1e38;
  }
  if (cls == kExtremeTf) {
    RenderSettings& s = c.settings;
    ChannelSettings& ch = s.channels[0];
    s.density = r.log_uni(1e-6, 1e4);
    const double maxv = dtype_max(v.dtype);
    switch (r.integer(0, 3)) {
      case 0: {  // very narrow window
        const double lo = r.uni(0.0, 0.9) * maxv;
        ch.window_lo = lo;
        ch.window_hi = lo + maxv * r.log_uni(1e-6, 1e-3);
        break;
      }
      case 1:  // very wide window
        ch.window_lo = -maxv * r.log_uni(1.0, 1e6);
        ch.window_hi = maxv * r.log_uni(1.0, 1e6);
        break;
      case 2: ch.gamma = r.log_uni(0.01, 100.0); break;
      default: {  // hard step in opacity and colour
        const double x = r.uni(0.05, 0.95);
        ch.opacity_points = {{0.0, 0.0}, {x, 0.0}, {std::min(1.0, x + 1e-3), 1.0}, {1.0, 1.0}};
        ch.color_points = {{0.0, {0, 0, 1}}, {x, {0, 0, 1}}, {std::min(1.0, x + 1e-3), {1, 0, 0}}, {1.0, {1, 1, 0}}};
        break;
      }
    }
    const std::vector<double> eps = {0.0, 1e-6, 1.0 / 512.0, 1e-2};
    s.early_termination = r.pick(eps);
  }
  if (cls == kFineStep) c.settings.step_voxels = r.log_uni(1.0 / 64.0, 1.0 / 8.0);
  if (cls == kCoarseStep) c.settings.step_voxels = r.log_uni(2.0, 8.0);

  // Camera.
  const dvec3 d = v.voxel_count() ? dims_of(v) : dvec3(1.0);
  switch (cls) {
    case kAxisParallel: {
      const int a = r.integer(0, 2);
      const double sign = r.chance(0.5) ? 1.0 : -1.0;
      dvec3 eye;
      for (int k = 0; k < 3; ++k) {
        // Lateral position: a face, a voxel boundary, a voxel centre or anywhere.
        const std::vector<double> choices = {0.0, d[k], std::floor(d[k] / 2), std::floor(d[k] / 2) + 0.5,
                                             r.uni(0.0, d[k])};
        eye[k] = r.pick(choices);
      }
      eye[a] = sign > 0 ? -r.uni(0.5, 3.0) * d[a] : d[a] * (1.0 + r.uni(0.5, 3.0));
      if (r.chance(0.2)) eye[a] = sign > 0 ? 0.0 : d[a];  // and from the face itself
      dvec3 dir(0.0);
      dir[a] = sign;
      c.camera = look(v, eye, dir, r);
      c.note = "axis " + std::to_string(a);
      break;
    }
    case kGrazing: {
      // Eye in the plane of face (a, side), outside the box along b, looking along b.
      const int a = r.integer(0, 2);
      const int b = (a + r.integer(1, 2)) % 3;
      const int o = 3 - a - b;
      dvec3 eye;
      eye[a] = r.chance(0.5) ? 0.0 : d[a];
      eye[o] = r.chance(0.5) ? r.uni(0.0, d[o]) : std::floor(d[o] / 2);
      eye[b] = -r.uni(0.5, 3.0) * d[b];
      dvec3 dir(0.0);
      dir[b] = 1.0;
      if (r.chance(0.5)) dir[a] = (r.chance(0.5) ? 1.0 : -1.0) * r.log_uni(1e-7, 1e-3);  // nearly in the plane
      c.camera = look(v, eye, dir, r);
      c.note = "face axis " + std::to_string(a) + " along " + std::to_string(b);
      break;
    }
    case kEyeOnFace:
    case kEyeOnEdge:
    case kEyeOnCorner: {
      const int fixed = cls == kEyeOnFace ? 1 : cls == kEyeOnEdge ? 2 : 3;
      dvec3 eye = d * dvec3(r.uni(0.05, 0.95), r.uni(0.05, 0.95), r.uni(0.05, 0.95));
      std::vector<int> axes = {0, 1, 2};
      std::shuffle(axes.begin(), axes.end(), r.g);
      for (int k = 0; k < fixed; ++k) eye[axes[k]] = r.chance(0.5) ? 0.0 : d[axes[k]];
      // Mostly into the box, sometimes straight out of it or along the face.
      dvec3 dir = glm::normalize(0.5 * d - eye + random_unit(r) * glm::length(d) * 0.3);
      if (r.chance(0.15)) dir = -dir;
      if (r.chance(0.15)) dir[axes[0]] = 0.0;
      if (glm::length(dir) < 1e-9) dir = dvec3(1, 0, 0);
      c.camera = look(v, eye, dir, r);
      break;
    }
    case kEyeInside: {
      const dvec3 eye = d * dvec3(r.uni(0.01, 0.99), r.uni(0.01, 0.99), r.uni(0.01, 0.99));
      c.camera = look(v, eye, random_unit(r), r);
      break;
    }
    default: c.camera = outside_view(v, r); break;
  }
  return c;
}

bool all_finite(const ImageRgbaF& image) {
  for (float f : image.rgba)
    if (!std::isfinite(f)) return false;
  return true;
}

double max_abs_difference(const ImageRgbaF& a, const ImageRgbaF& b) {
  if (a.width != b.width || a.height != b.height || a.rgba.size() != b.rgba.size())
    return std::numeric_limits<double>::infinity();
  double m = 0.0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    const double d = std::abs(double(a.rgba[i]) - double(b.rgba[i]));
    if (!(d <= m)) m = std::isnan(d) ? std::numeric_limits<double>::infinity() : d;
  }
  return m;
}

double fraction_over(const ImageRgbaF& a, const ImageRgbaF& b, double tolerance) {
  if (a.width != b.width || a.height != b.height || a.rgba.size() != b.rgba.size()) return 1.0;
  const size_t pixels = a.rgba.size() / 4;
  if (pixels == 0) return 0.0;
  size_t over = 0;
  for (size_t p = 0; p < pixels; ++p) {
    bool off = false;
    for (size_t k = 0; k < 4; ++k) off = off || !(std::abs(double(a.rgba[p * 4 + k]) - double(b.rgba[p * 4 + k])) <= tolerance);
    over += off;
  }
  return double(over) / double(pixels);
}

namespace {

// The colormap's steepest step in output per unit of windowed value: turbo
// and viridis move a channel several times faster than gray does. 1 when
// colour control points replace the colormap (their slopes count separately).
double colormap_slope(const ChannelSettings& ch) {
  double slope = 1.0;
  if (!ch.color_points.empty()) return slope;
  if (auto table = find_colormap(ch.colormap))
    for (size_t i = 1; i < table->size(); ++i)
      for (int k = 0; k < 3; ++k) slope = std::max(slope, std::abs((*table)[i][k] - (*table)[i - 1][k]) * 255.0);
  return slope;
}

}  // namespace

double case_flip_tolerance(const StabilityCase& c) {
  return std::min(1.0, stability_classes()[c.class_index].bound * colormap_slope(c.settings.channels[0]));
}

double case_bound(const StabilityCase& c) {
  const StabilityClass& cls = stability_classes()[c.class_index];
  const ChannelSettings& ch = c.settings.channels[0];
  const double width = ch.window_hi - ch.window_lo;
  // Window slope: the filter's value error relative to the window's width.
  double w = 1.0;
  if (c.volume.dtype == DType::kU8 || c.volume.dtype == DType::kU16) {
    w = dtype_max(c.volume.dtype) / width;
  } else {
    // Float textures: lavapipe filters them in float, but GPUs filter with
    // fixed-point weights (NVIDIA: 8 fractional bits) as they do for
    // integers, so the value error scales with the spread of the texel values
    // (+-Inf read as +-1e30) just as the dtype range does above.
    double lo = 0.0, hi = 0.0;
    for (uint64_t i = 0; i < c.volume.voxel_count(); ++i) {
      float f;
      std::memcpy(&f, &c.volume.data[i * 4], 4);
      const double v = renderable_value(f);
      lo = i ? std::min(lo, v) : v;
      hi = i ? std::max(hi, v) : v;
    }
    w = (hi - lo) / width;
  }
  // Steepest control-point segment (opacity and colour).
  double t = 1.0;
  for (size_t i = 1; i < ch.opacity_points.size(); ++i) {
    const double dx = ch.opacity_points[i].x - ch.opacity_points[i - 1].x;
    if (dx > 0) t = std::max(t, std::abs(ch.opacity_points[i].opacity - ch.opacity_points[i - 1].opacity) / dx);
  }
  t = std::max(t, colormap_slope(ch));
  for (size_t i = 1; i < ch.color_points.size(); ++i) {
    const double dx = ch.color_points[i].x - ch.color_points[i - 1].x;
    for (int k = 0; k < 3 && dx > 0; ++k)
      t = std::max(t, std::abs(ch.color_points[i].rgb[k] - ch.color_points[i - 1].rgb[k]) / dx);
  }
  double err = cls.bound * std::max(1.0, w) * t;
  if (ch.gamma > 1.0) err *= ch.gamma;
  if (ch.gamma < 1.0) err = std::pow(std::min(err, 1.0), ch.gamma);
  // Extinction beyond ~1 per step turns a small opacity error into a large one.
  err *= std::max(1.0, c.settings.density * c.settings.step_voxels);
  return std::min(1.0, err);
}

CaseOutcome run_stability_case(gpu::Context& ctx, const StabilityCase& c,
                               const std::shared_ptr<BrickPipelines>& pipelines) {
  CaseOutcome out;
  const StabilityClass& cls = stability_classes()[c.class_index];
  out.bound = c.expect_rejection ? 0.0 : case_bound(c);
  auto renderer = MemoryVolumeRenderer::create(ctx, {c.volume}, 64, pipelines);
  const Status loaded = renderer.status();
  std::span<const DenseVolume> one(&c.volume, 1);
  ReferenceOptions ro;
  ro.step_voxels = c.settings.step_voxels;
  ro.threads = 1;
  ro.grid_from_eye = true;  // the brick renderer's samples
  if (c.expect_rejection) {
    auto ref = render_reference(one, c.camera, c.settings, c.width, c.height, ro);
    if (loaded.code() != ErrorCode::kInvalidArgument || ref.status().code() != ErrorCode::kInvalidArgument) {
      out.failure = "expected both renderers to refuse the " + std::string(cls.name) + " volume; GPU: " +
                    loaded.to_string() + ", reference: " + ref.status().to_string();
      return out;
    }
    out.passed = true;
    return out;
  }
  if (!loaded.is_ok()) {
    out.failure = "set_volume: " + loaded.to_string();
    return out;
  }
  auto gpu = (*renderer)->render_float(c.camera, c.settings, c.width, c.height);
  if (!gpu) {
    out.failure = "GPU render: " + gpu.status().to_string();
    return out;
  }
  auto ref = render_reference(one, c.camera, c.settings, c.width, c.height, ro);
  if (!ref) {
    out.failure = "reference render: " + ref.status().to_string();
    return out;
  }
  out.non_finite = !all_finite(*gpu) || !all_finite(*ref);
  out.max_abs = max_abs_difference(*gpu, *ref);
  out.capped = out.bound >= 1.0;
  out.over_fraction = fraction_over(*gpu, *ref, case_flip_tolerance(c));

  if (out.non_finite) {
    out.failure = "NaN or Inf in an output channel";
  } else if (out.capped && !(out.over_fraction <= kCappedOverFraction)) {
 out.failure = std::to_string(out.over_fraction * 100.0) + "% of pixels are off by more than " +
                  std::to_string(case_flip_tolerance(c) * 255.0) + "/255 (at most " + std::to_string(kCappedOverFraction * 100.0) +
                  "% may be where the case's gain makes max-abs meaningless)";
  } else if (!(out.max_abs <= out.bound)) {
    out.failure = "max-abs error " + std::to_string(out.max_abs * 255.0) + "/255 exceeds the " + cls.name +
                  " bound " + std::to_string(out.bound * 255.0) + "/255";
  } else {
    out.passed = true;
  }
  return out;
}

}  // namespace vxr::bench

#include "render/reference_renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "core/trace.h"
#include "render/raycast_setup.h"
#include "render/transfer_function.h"

namespace vxr {
namespace {

// The shader's per-pixel jitter (raycast_core.glsl vxr_jitter), bit for bit:
// an integer hash, its top 24 bits as a fraction in [0, 1).
double pixel_jitter(uint32_t x, uint32_t y) {
  uint32_t h = (x * 0x8da6b343u) ^ (y * 0xd8163841u);
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return double(h >> 8) * (1.0 / 16777216.0);
}

using glm::dvec3;
using glm::dvec4;

struct Volumes {
  std::array<std::vector<double>, VXR_MAX_CHANNELS> texels;  // texel units, x fastest
  int nx = 1, ny = 1, nz = 1;
  int channels = 1;

  // Trilinear with clamp-to-edge, voxel centres at i + 0.5 (the GPU's convention).
  double channel(int c, const dvec3& pos) const {
    const std::vector<double>& t = texels[c];
    const double px = pos.x - 0.5, py = pos.y - 0.5, pz = pos.z - 0.5;
    const double fx0 = std::floor(px), fy0 = std::floor(py), fz0 = std::floor(pz);
    const double fx = px - fx0, fy = py - fy0, fz = pz - fz0;
    auto cl = [](double v, int n) { return static_cast<size_t>(std::clamp(static_cast<long long>(v), 0LL, (long long)n - 1)); };
    const size_t x0 = cl(fx0, nx), x1 = cl(fx0 + 1, nx), y0 = cl(fy0, ny), y1 = cl(fy0 + 1, ny), z0 = cl(fz0, nz),
                 z1 = cl(fz0 + 1, nz);
    auto at = [&](size_t x, size_t y, size_t z) { return t[(z * ny + y) * nx + x]; };
    const double c00 = at(x0, y0, z0) * (1 - fx) + at(x1, y0, z0) * fx;
    const double c10 = at(x0, y1, z0) * (1 - fx) + at(x1, y1, z0) * fx;
    const double c01 = at(x0, y0, z1) * (1 - fx) + at(x1, y0, z1) * fx;
    const double c11 = at(x0, y1, z1) * (1 - fx) + at(x1, y1, z1) * fx;
    return (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz;
  }
  dvec4 sample(const dvec3& pos) const {
    dvec4 v(0.0);
    for (int c = 0; c < channels; ++c) v[c] = channel(c, pos);
    return v;
  }
};

struct Ray {
  dvec4 acc[VXR_MAX_CHANNELS] = {dvec4(0), dvec4(0), dvec4(0), dvec4(0)};
  dvec4 tau{0.0};
  dvec4 reduce{0.0};
  dvec4 reduce_depth{0.0};
  double count = 0.0;
  double prev_value = -1.0, prev_t = 0.0, hit_t = -1.0;
  double density = 0.0;  // extinction at TF opacity 1 per unit of t (ray_density)
  bool done = false;
};

double opacity(double tau) { return -std::expm1(-tau); }

class Tracer {
 public:
  Tracer(const Volumes& v, const RaycastSetup& s, const TransferTable& tf, const ReferenceOptions& o)
      : v_(v), s_(s), tf_(tf), step_(o.step_voxels), fhat_(glm::normalize(s.rays.forward)), opt_(o) {}

  dvec4 normalise(const dvec4& raw) const {
    dvec4 x;
    for (int c = 0; c < VXR_MAX_CHANNELS; ++c) {
      const dvec4& w = s_.window[c];
      const double v = std::clamp((raw[c] - w.x) / (w.y - w.x), 0.0, 1.0);
      x[c] = w.z == 1.0 ? v : std::pow(v, w.z);
    }
    return x;
  }
  dvec4 value(const dvec3& pos) const { return normalise(v_.sample(pos)); }

  double depth_coord(const dvec3& pos) const {
    if (s_.depth_mode == DepthColorMode::kView)
      return std::clamp((glm::dot(pos - s_.rays.eye, fhat_) - s_.depth_lo) / (s_.depth_hi - s_.depth_lo), 0.0, 1.0);
    const int axis = static_cast<int>(s_.depth_mode) - static_cast<int>(DepthColorMode::kAxisX);
    return std::clamp(pos[axis] / s_.dims[axis], 0.0, 1.0);
  }

  void gradients(const dvec3& p, dvec4& gx, dvec4& gy, dvec4& gz) const {
    gx = 0.5 * (value(p + dvec3(1, 0, 0)) - value(p - dvec3(1, 0, 0)));
    gy = 0.5 * (value(p + dvec3(0, 1, 0)) - value(p - dvec3(0, 1, 0)));
    gz = 0.5 * (value(p + dvec3(0, 0, 1)) - value(p - dvec3(0, 0, 1)));
  }

  void step(Ray& r, const dvec3& eye, const dvec3& dir, double t, double seg) const {
    const dvec3 pos = eye + t * dir;
    const dvec4 x = value(pos);
    const int n = static_cast<int>(s_.channels);
    const bool depth_color = s_.depth_mode != DepthColorMode::kOff;
    const OpticalModel m = s_.model;
    if (m == OpticalModel::kMip || m == OpticalModel::kMinIp) {
      const double dc = depth_color ? depth_coord(pos) : 0.0;
      for (int c = 0; c < n; ++c) {
        const bool better = m == OpticalModel::kMip ? x[c] > r.reduce[c] : x[c] < r.reduce[c];
        if (better) r.reduce[c] = x[c], r.reduce_depth[c] = dc;
      }
      r.count += 1.0;
      return;
    }
    if (m == OpticalModel::kAverage) {
      r.reduce += x * seg;
      r.count += seg;
      return;
    }
    if (m == OpticalModel::kIsosurface) {
      const double v = x[s_.iso_channel];
      if (v >= s_.iso_norm) {
        r.hit_t = r.prev_value < 0.0 ? t : r.prev_t + (s_.iso_norm - r.prev_value) / (v - r.prev_value) * (t - r.prev_t);
        r.done = true;
      }
      r.prev_value = v;
      r.prev_t = t;
      return;
    }
    dvec4 gfac(1.0);
    if (s_.gradient) {
      dvec4 gx, gy, gz;
      gradients(pos, gx, gy, gz);
      for (int c = 0; c < VXR_MAX_CHANNELS; ++c) {
        const double mag = std::sqrt(gx[c] * gx[c] + gy[c] * gy[c] + gz[c] * gz[c]);
        gfac[c] = std::clamp((mag - s_.gradient_lo) / (s_.gradient_hi - s_.gradient_lo), 0.0, 1.0);
      }
    }
    const double dc = depth_color ? depth_coord(pos) : 0.0;
    dvec3 mix_color(0.0);
    double mix_tau = 0.0;
    for (int c = 0; c < n; ++c) {
      if (s_.window[c].w == 0.0) continue;
      const dvec4 tf = tf_.lookup(c, x[c]);
      const dvec3 color = depth_color ? dvec3(tf_.lookup(c, dc)) : dvec3(tf);
      const double tau = tf.a * gfac[c] * r.density * seg;
      if (m == OpticalModel::kEmission) {
        r.acc[c] += dvec4(color * tau, 0.0);
      } else if (s_.blend == ChannelBlend::kAdditive) {
        r.acc[c] += dvec4(std::exp(-r.tau[c]) * opacity(tau) * color, 0.0);
        r.tau[c] += tau;
      } else {
        mix_color += tau * color;
        mix_tau += tau;
      }
    }
    if (m == OpticalModel::kEmission) return;
    if (s_.blend == ChannelBlend::kComposite) {
      if (mix_tau > 0.0) r.acc[0] += dvec4(std::exp(-r.tau.x) * opacity(mix_tau) * (mix_color / mix_tau), 0.0);
      r.tau.x += mix_tau;
      r.done = std::exp(-r.tau.x) <= s_.epsilon;
    } else {
      double tmin = 1e300;
      for (int c = 0; c < n; ++c)
        if (s_.window[c].w != 0.0) tmin = std::min(tmin, r.tau[c]);
      r.done = std::exp(-tmin) <= s_.epsilon;
    }
  }

  dvec4 finish(const Ray& r, const dvec3& eye, const dvec3& dir) const {
    const int n = static_cast<int>(s_.channels);
    const bool depth_color = s_.depth_mode != DepthColorMode::kOff;
    const OpticalModel m = s_.model;
    auto clamp3 = [](dvec3 v) { return glm::clamp(v, 0.0, 1.0); };
    if (m == OpticalModel::kEmissionAbsorption || m == OpticalModel::kEmission) {
      dvec3 rgb(0.0);
      double tau = 0.0;
      for (int c = 0; c < n; ++c) rgb += dvec3(r.acc[c]), tau += r.tau[c];
      if (m == OpticalModel::kEmission) return dvec4(clamp3(rgb), 0.0);
      return dvec4(clamp3(rgb), opacity(tau));
    }
    if (m == OpticalModel::kIsosurface) {
      if (r.hit_t < 0.0) return dvec4(0.0);
      const dvec3 pos = eye + r.hit_t * dir;
      const int ic = static_cast<int>(s_.iso_channel);
      dvec4 gx, gy, gz;
      gradients(pos, gx, gy, gz);
      const dvec3 g(gx[ic], gy[ic], gz[ic]);
      const double ndl = glm::dot(g, g) > 0.0 ? std::abs(glm::dot(glm::normalize(g), dir)) : 1.0;
      const dvec3 base(tf_.lookup(ic, depth_color ? depth_coord(pos) : s_.iso_norm));
      const dvec3 rgb = base * (s_.shading.ambient + s_.shading.diffuse * ndl) +
                        dvec3(s_.shading.specular * std::pow(ndl, s_.shading.shininess));
      return dvec4(clamp3(rgb), 1.0);
    }
    if (r.count <= 0.0) return dvec4(0.0);
    dvec3 rgb(0.0);
    double transparency = 1.0;
    for (int c = 0; c < n; ++c) {
      if (s_.window[c].w == 0.0) continue;
      const double v = m == OpticalModel::kAverage ? r.reduce[c] / r.count : r.reduce[c];
      const dvec4 tf = tf_.lookup(c, v);
      const dvec3 color = depth_color && m != OpticalModel::kAverage ? dvec3(tf_.lookup(c, r.reduce_depth[c])) : dvec3(tf);
      rgb += color * tf.a;
      transparency *= 1.0 - tf.a;
    }
    return dvec4(clamp3(rgb), 1.0 - transparency);
  }

  dvec4 cast(uint32_t px, uint32_t py) const {
    const double ndx = (2.0 * px + 1.0 - s_.width) / s_.width, ndy = (2.0 * py + 1.0 - s_.height) / s_.height;
    const dvec3 dir = glm::normalize(s_.rays.forward + ndx * s_.rays.right - ndy * s_.rays.up);
    const dvec3 eye = s_.rays.eye;
    // Slab test with the axis-parallel case branched out. A ray lying in a
    // face plane belongs to the box when the plane is its low face and not
    // when it is its high face ([0, dims) per axis, as the GPU's slab test
    // decides it): neighbouring bricks then never both claim a ray.
    double t0 = 0.0, t1 = 1e300;
    for (int a = 0; a < 3; ++a) {
      const double lo = std::max(0.0, opt_.clip_lo[a]), hi = std::min(double(s_.dims[a]), opt_.clip_hi[a]);
      if (dir[a] == 0.0) {
        if (eye[a] < lo || eye[a] >= hi) return dvec4(0.0);
        continue;
      }
      double ta = (lo - eye[a]) / dir[a], tb = (hi - eye[a]) / dir[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    const dvec3 pn(opt_.plane);
    if (pn != dvec3(0.0)) {  // keep dot(n, eye + t dir) + w >= 0
      const double num = glm::dot(pn, eye) + opt_.plane.w, den = glm::dot(pn, dir);
      if (den > 0.0) t0 = std::max(t0, -num / den);
      else if (den < 0.0) t1 = std::min(t1, -num / den);
      else if (num < 0.0) return dvec4(0.0);
    }
    if (!opt_.view_depth.empty()) {
      // A view depth z lies at t = z * |raw direction| (the raw direction has unit view depth), as on the GPU.
      const double z = opt_.view_depth[size_t(py) * s_.width + px];
      t1 = std::min(t1, z * glm::length(s_.rays.forward + ndx * s_.rays.right - ndy * s_.rays.up));
    }
    if (!(t1 > t0)) return dvec4(0.0);
    Ray r;
    r.density = ray_density(s_, dir);
    if (s_.model == OpticalModel::kMinIp) r.reduce = dvec4(1.0);
    if (opt_.grid_from_eye) {
      const double o = s_.jitter ? pixel_jitter(px, py) : s_.sample_offset;
      const double i0 = std::ceil(t0 / step_ - o), i1 = std::ceil(t1 / step_ - o);
      for (double i = i0; i < i1 && !r.done; ++i) step(r, eye, dir, (i + o) * step_, step_);
      return finish(r, eye, dir);
    }
    const double len = t1 - t0;
    const uint64_t n = static_cast<uint64_t>(std::ceil(len / step_));
    for (uint64_t i = 0; i < n && !r.done; ++i) {
      const double a = t0 + i * step_;
      const double b = std::min(t0 + (i + 1) * step_, t1);
      if (b <= a) continue;
      step(r, eye, dir, a + 0.5 * (b - a), b - a);
    }
    return finish(r, eye, dir);
  }

 private:
  const Volumes& v_;
  const RaycastSetup& s_;
  const TransferTable& tf_;
  double step_;
  dvec3 fhat_;
  const ReferenceOptions& opt_;
};

}  // namespace

Result<ImageRgbaF> render_reference(std::span<const DenseVolume> channels, const Camera& camera,
                                    const RenderSettings& settings, uint32_t width, uint32_t height,
                                    const ReferenceOptions& options) {
  VXR_TRACE_SCOPE("reference.render");
  if (channels.empty() || channels.size() > VXR_MAX_CHANNELS)
    return invalid_argument("the reference renderer takes 1 to 4 channels");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  if (!(options.step_voxels > 0.0)) return invalid_argument("reference step must be > 0 voxels");
  if (!options.view_depth.empty() && options.view_depth.size() != size_t(width) * height)
    return invalid_argument("reference: the depth image has " + std::to_string(options.view_depth.size()) +
                            " values for " + std::to_string(width) + "x" + std::to_string(height) + " pixels");
  VXR_RETURN_IF_ERROR(validate_render_settings(settings, static_cast<uint32_t>(channels.size())));
  Volumes vols;
  vols.nx = channels[0].dims[0];
  vols.ny = channels[0].dims[1];
  vols.nz = channels[0].dims[2];
  vols.channels = static_cast<int>(channels.size());
  std::vector<double> scales;
  for (size_t c = 0; c < channels.size(); ++c) {
    const DenseVolume& v = channels[c];
    if (v.dims != channels[0].dims) return invalid_argument("all channels must have the same dims");
    VXR_RETURN_IF_ERROR(check_renderable(v));
    const double scale = v.dtype == DType::kU8 ? 255.0 : v.dtype == DType::kU16 ? 65535.0 : 1.0;
    scales.push_back(scale);
    auto& t = vols.texels[c];
    t.resize(v.voxel_count());
    size_t i = 0;
    for (uint32_t z = 0; z < v.dims[2]; ++z)
      for (uint32_t y = 0; y < v.dims[1]; ++y)
        for (uint32_t x = 0; x < v.dims[0]; ++x) t[i++] = renderable_value(v.value_at(x, y, z)) / scale;
  }
  const VolumePlacement placement{channels[0].dims, channels[0].voxel_size,
                                  {channels[0].origin[0], channels[0].origin[1], channels[0].origin[2]}};
  const RaycastSetup setup = plan_raycast(camera, settings, placement, scales, width, height);
  const TransferTable table = build_transfer_table(settings);
  const Tracer tracer(vols, setup, table, options);

  ImageRgbaF img{width, height, std::vector<float>(size_t(width) * height * 4)};
  std::atomic<uint32_t> next_row{0};
  auto work = [&] {
    for (uint32_t y; (y = next_row.fetch_add(1)) < height;)
      for (uint32_t x = 0; x < width; ++x) {
        const dvec4 c = tracer.cast(x, y);
        for (int k = 0; k < 4; ++k) img.rgba[(size_t(y) * width + x) * 4 + k] = static_cast<float>(c[k]);
      }
  };
  unsigned n = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned i = 1; i < n; ++i) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return img;
}

}  // namespace vxr

#include "render/lod/brick_pool.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <limits>
#include <string>
#include <thread>

#include "core/trace.h"
#include "shared/brick_params.h"
#include "shared/raycast_params.h"
#include "volume/dense_volume.h"

namespace vxr {

VkFormat brick_texel_format(DType dtype) {
  switch (dtype) {
    case DType::kU8: return VK_FORMAT_R8_UNORM;
    case DType::kU16: return VK_FORMAT_R16_UNORM;
    default: return VK_FORMAT_R32_SFLOAT;
  }
}

void write_texel_words(VkFormat texel_format, const uint8_t* row, const uint8_t* next_row, uint32_t n, uint8_t* out) {
  if (texel_word_width(texel_format) == 4) {
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t x1 = x + 1 < n ? x + 1 : x;
      out[4 * x] = row[x];
      out[4 * x + 1] = row[x1];
      out[4 * x + 2] = next_row[x];
      out[4 * x + 3] = next_row[x1];
    }
    return;
  }
  for (uint32_t x = 0; x < n; ++x) {  // u16: the texel's two bytes, then its +x neighbour's
    const uint32_t x1 = x + 1 < n ? x + 1 : x;
    std::memcpy(out + 4 * x, row + 2 * x, 2);
    std::memcpy(out + 4 * x + 2, row + 2 * x1, 2);
  }
}

double brick_value_scale(DType dtype) {
  switch (dtype) {
    case DType::kU8: return 255.0;
    case DType::kU16: return 65535.0;
    default: return 1.0;
  }
}

// Native voxels -> atlas texels: u8/u16 as they are, everything else as float
// in data units (NaN to 0, clamped to +-1e30: the dense path's renderable_value).
void convert_to_texels(DType dtype, const uint8_t* in, size_t n, uint8_t* out) {
  auto to_float = [&](auto tag) {
    using T = decltype(tag);
    float* o = reinterpret_cast<float*>(out);
    for (size_t i = 0; i < n; ++i) {
      T v;
      std::memcpy(&v, in + i * sizeof(T), sizeof(T));
      o[i] = static_cast<float>(renderable_value(static_cast<double>(v)));
    }
  };
  switch (dtype) {
    case DType::kU8: std::memcpy(out, in, n); break;
    case DType::kU16: std::memcpy(out, in, n * 2); break;
    case DType::kI8: to_float(int8_t{}); break;
    case DType::kI16: to_float(int16_t{}); break;
    case DType::kU32: to_float(uint32_t{}); break;
    case DType::kI32: to_float(int32_t{}); break;
    case DType::kF32: to_float(float{}); break;
  }
}

BrickCells brick_cells_for(uint32_t chunk_size, uint32_t cell_voxels) {
  BrickCells c;
  c.cell_size = std::max({cell_voxels, (chunk_size + 31) / 32, 1u});
  // Cells k = 0 .. n-1 reach local n * s - 0.5: past the chunk's last position.
  c.cells_per_axis = chunk_size / c.cell_size + 1;
  return c;
}

namespace {

// Min and max of `in` over each cell's texel range, one axis at a time:
// z over whole planes, then y over whole rows (both plain element-wise loops
// the compiler vectorises), then x within the n*n remaining rows. The same
// voxels as the direct 3D loop, each read about once instead of about twice.
// Start values that every texel replaces, except a NaN (as std::min/max from +-inf).
template <typename T>
constexpr T kHighest = std::numeric_limits<T>::has_infinity ? std::numeric_limits<T>::infinity()
                                                             : std::numeric_limits<T>::max();
template <typename T>
constexpr T kLowest = std::numeric_limits<T>::has_infinity ? -std::numeric_limits<T>::infinity()
                                                            : std::numeric_limits<T>::lowest();

template <typename T>
void cell_min_max(const T* in, uint32_t edge, uint32_t n, const std::vector<uint32_t>& lo,
                  const std::vector<uint32_t>& hi, std::vector<T>& out_lo, std::vector<T>& out_hi) {
  const size_t plane = size_t(edge) * edge;
  // Scratch kept per thread: every element is written before it is read, and
  // a fresh allocation of this size (~150 KiB per u8 brick in 2-voxel cells)
  // costs page faults and zeroing on every brick staged.
  static thread_local std::vector<T> zlo, zhi, ylo, yhi;
  zlo.resize(n * plane), zhi.resize(n * plane);  // [cz][y][x]
  for (uint32_t c = 0; c < n; ++c) {
    T* l = zlo.data() + c * plane;
    T* h = zhi.data() + c * plane;
    std::fill_n(l, plane, kHighest<T>);
    std::fill_n(h, plane, kLowest<T>);
    for (uint32_t z = lo[c]; z <= hi[c]; ++z) {
      const T* p = in + z * plane;
      for (size_t i = 0; i < plane; ++i) {
        l[i] = p[i] < l[i] ? p[i] : l[i];  // a NaN never replaces a number (as std::min)
        h[i] = h[i] < p[i] ? p[i] : h[i];
      }
    }
  }
  ylo.resize(size_t(n) * n * edge), yhi.resize(size_t(n) * n * edge);  // [cz][cy][x]
  for (uint32_t cz = 0; cz < n; ++cz)
    for (uint32_t c = 0; c < n; ++c) {
      T* l = ylo.data() + (size_t(cz) * n + c) * edge;
      T* h = yhi.data() + (size_t(cz) * n + c) * edge;
      const T* pl = zlo.data() + cz * plane;
      const T* ph = zhi.data() + cz * plane;
      std::copy_n(pl + size_t(lo[c]) * edge, edge, l);
      std::copy_n(ph + size_t(lo[c]) * edge, edge, h);
      for (uint32_t y = lo[c] + 1; y <= hi[c]; ++y)
        for (uint32_t x = 0; x < edge; ++x) {
          const T a = pl[size_t(y) * edge + x], b = ph[size_t(y) * edge + x];
          l[x] = a < l[x] ? a : l[x];
          h[x] = h[x] < b ? b : h[x];
        }
    }
  out_lo.resize(size_t(n) * n * n);
  out_hi.resize(size_t(n) * n * n);
  for (size_t row = 0; row < size_t(n) * n; ++row)
    for (uint32_t c = 0; c < n; ++c) {
      T l = ylo[row * edge + lo[c]], h = yhi[row * edge + lo[c]];
      for (uint32_t x = lo[c] + 1; x <= hi[c]; ++x) {
        const T a = ylo[row * edge + x], b = yhi[row * edge + x];
        l = a < l ? a : l;
        h = h < b ? b : h;
      }
      out_lo[row * n + c] = l;
      out_hi[row * n + c] = h;
    }
}

// `unorm_max`: the texel value that means 1 (1 for floats).
template <typename T>
void cell_ranges_as_float(const T* texels, uint32_t edge, const BrickCells& cells, uint32_t apron, float unorm_max,
                          glm::vec2* out) {
  const uint32_t n = cells.cells_per_axis, s = cells.cell_size;
  // Slot texel ranges of cell k along an axis, clipped to the slot: the
  // voxels a sample inside it filters (local k*s - 1 .. k*s + s - 1), and
  // those one voxel further, which a sample within the band filters too.
  const auto clip = [&](int64_t v) { return uint32_t(std::clamp<int64_t>(v + apron, 0, edge - 1)); };
  std::vector<uint32_t> lo(n), hi(n), ring_lo(n), ring_hi(n);
  for (uint32_t k = 0; k < n; ++k) {
    lo[k] = clip(int64_t(k) * s - 1);
    hi[k] = clip(int64_t(k) * s + s - 1);
    ring_lo[k] = clip(int64_t(k) * s - 2);
    ring_hi[k] = clip(int64_t(k) * s + s);
  }
  std::vector<T> mn, mx, ring_mn, ring_mx;
  cell_min_max(texels, edge, n, lo, hi, mn, mx);
  cell_min_max(texels, edge, n, ring_lo, ring_hi, ring_mn, ring_mx);
  // A sample up to `band` outside the cell gives the ring at most that much
  // of its weight per axis, 1 - (1 - band)^3 < 3 * band in all.
  const float ring_weight = float(3.0 * VXR_CELL_BAND);
  for (size_t i = 0; i < mn.size(); ++i) {
    // Texel to float is monotone, so the float of the extreme texel is the extreme float.
    float l = float(mn[i]) / unorm_max, h = float(mx[i]) / unorm_max;
    const float rl = float(ring_mn[i]) / unorm_max, rh = float(ring_mx[i]) / unorm_max;
    if (rl < l) l = (1.0f - ring_weight) * l + ring_weight * rl;
    if (rh > h) h = (1.0f - ring_weight) * h + ring_weight * rh;
    // Filtering mixes values with rounded weights: widen by far more than its rounding.
    constexpr float kRel = float(VXR_CELL_PAD_REL), kAbs = float(VXR_CELL_PAD_ABS);
    const float pad_lo = std::abs(l) * kRel + kAbs, pad_hi = std::abs(h) * kRel + kAbs;
    out[i] = glm::vec2(l - pad_lo, h + pad_hi);
  }
}

}  // namespace

void compute_cell_ranges(VkFormat format, const uint8_t* texels, uint32_t chunk_size, uint32_t apron,
                         const BrickCells& cells, glm::vec2* out) {
  const uint32_t edge = chunk_size + 2 * apron;
  if (format == VK_FORMAT_R8_UNORM) return cell_ranges_as_float(texels, edge, cells, apron, 255.0f, out);
  const size_t n = size_t(edge) * edge * edge;
  if (format == VK_FORMAT_R16_UNORM) {
    std::vector<uint16_t> v(n);
    std::memcpy(v.data(), texels, n * 2);
    return cell_ranges_as_float(v.data(), edge, cells, apron, 65535.0f, out);
  }
  std::vector<float> v(n);
  std::memcpy(v.data(), texels, n * 4);
  cell_ranges_as_float(v.data(), edge, cells, apron, 1.0f, out);
}

Result<glm::uvec3> fit_slots(glm::uvec3 wanted, uint32_t edge, uint32_t texel_bytes, uint32_t max_dim,
                             uint64_t max_bytes, uint32_t wide_x) {
  const uint64_t brick_bytes = uint64_t(edge) * edge * edge * texel_bytes;
  if (uint64_t(edge) * wide_x > max_dim || brick_bytes > max_bytes)
    return out_of_range("brick pool: one brick of " + std::to_string(edge) + "^3 texels does not fit the device (" +
                        std::to_string(max_dim) + " texels a side, " + std::to_string(max_bytes >> 20) +
                        " MiB); import with a smaller --chunk");
  glm::uvec3 s;
  for (int a = 0; a < 3; ++a) s[a] = std::max(1u, std::min(wanted[a], max_dim / (edge * (a == 0 ? wide_x : 1))));
  // Shrink the longest axis until the atlas fits the heap; at least one slot always fits (checked above).
  while (uint64_t(s.x) * s.y * s.z * brick_bytes > max_bytes) {
    const int a = s.x >= s.y && s.x >= s.z ? 0 : (s.y >= s.z ? 1 : 2);
    --s[a];
  }
  return s;
}

Result<std::unique_ptr<BrickPool>> BrickPool::create(gpu::Context& ctx, const ChunkSource& source,
                                                     const BrickPoolOptions& options) {
  std::unique_ptr<BrickPool> p(new BrickPool(ctx, source));
  const DType dtype = source.info().dtype;
  const VkFormat format = brick_texel_format(dtype);
  p->texel_bytes_ = gpu::format_texel_bytes(format);
  if (format == VK_FORMAT_R32_SFLOAT) {
    VkFormatProperties props;
    vkGetPhysicalDeviceFormatProperties(ctx.physical_device(), format, &props);
    if (!(props.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT))
      return unsupported("brick pool: " + ctx.info().name + " cannot filter R32_SFLOAT 3D textures; " +
                         dtype_name(dtype) + " volumes need it");
  }
  glm::uvec3 slots = options.slots;
  const bool auto_slots = slots == glm::uvec3(0);
  if (!auto_slots && (slots.x == 0 || slots.y == 0 || slots.z == 0))
    return invalid_argument("brick pool: every axis needs at least one slot");
  if (options.apron > 4) return invalid_argument("brick pool: an apron of at most 4 voxels, not " +
                                                 std::to_string(options.apron));
  p->channel_map_ = options.channels;
  if (p->channel_map_.empty())
    for (uint32_t c = 0; c < std::min<uint32_t>(source.info().channels, VXR_MAX_CHANNELS); ++c)
      p->channel_map_.push_back(c);
  if (p->channel_map_.size() > VXR_MAX_CHANNELS)
    return invalid_argument("brick pool: " + std::to_string(p->channel_map_.size()) + " channels asked for, at most " +
                            std::to_string(VXR_MAX_CHANNELS) + " are drawn together");
  for (uint32_t c : p->channel_map_)
    if (c >= source.info().channels)
      return invalid_argument("brick pool: channel " + std::to_string(c) + " asked for, the volume has " +
                              std::to_string(source.info().channels));
  const uint32_t nch = static_cast<uint32_t>(p->channel_map_.size());
  p->apron_ = std::max(options.apron, source.apron());
  p->edge_ = source.chunk_size() + 2 * p->apron_;
  p->channel_bytes_ = uint64_t(p->edge_) * p->edge_ * p->edge_ * p->texel_bytes_;
  p->brick_bytes_ = p->channel_bytes_ * nch;
  // Texel views (see above): a CPU device with direct writes.
  const bool want_views = options.texel_views && options.direct_writes && texel_word_width(format) != 0 &&
                          ctx.info().is_cpu();
  // Texel words take texel_word_width times the bytes (and width) per atlas texel.
  const uint32_t stored = want_views ? texel_word_width(format) : 1;
  const uint64_t view_bytes =
      uint64_t(ctx.limits().maxTexelBufferElements) * gpu::format_texel_bytes(kAtlasTexelElement);
  // The source's bricks: every level and timepoint.
  uint64_t bricks = 0;
  for (const LevelInfo& li : source.levels())
    bricks += uint64_t(li.chunk_counts[0]) * li.chunk_counts[1] * li.chunk_counts[2];
  bricks = std::max<uint64_t>(bricks * std::max<uint32_t>(source.info().timepoints, 1), 1);
  if (auto_slots) {
    // Halve the largest axis until the atlases fit (at least 2 x 2 x 2); with
    // texel views then lower it by one until each atlas fits one view (a u8
    // or u16 slot of 68^3 in lavapipe's 128 Mi elements: 7 x 7 x 8 slots,
    // where halving would leave 4 x 8 x 8).
    slots = {16, 16, 8};
    const auto count = [&] { return uint64_t(slots.x) * slots.y * slots.z; };
    auto largest = [&]() -> uint32_t& {
      return slots.x >= slots.y && slots.x >= slots.z ? slots.x : slots.y >= slots.z ? slots.y : slots.z;
    };
    while (count() * p->brick_bytes_ * stored > options.auto_atlas_bytes && count() > 8) largest() /= 2;
    while (want_views && count() * p->channel_bytes_ * stored > view_bytes && count() > 8) --largest();
    // A small source: no more than twice its bricks, so it still preloads
    // (BrickRenderer::preload_if_fits pins what fits in half the pool) but
    // holds no atlas it never fills (the bundled MRI: 392 slots, 493 MB, for
    // its 17 bricks; now 36). Pictures don't depend on the slots (atlas_corners).
    while (largest() > 1 && count() / largest() * (largest() - 1) >= 2 * bricks) --largest();
  }
  // Lowered further to fit the device, so containers with wide chunks (up to 512 + apron) still draw.
  VXR_ASSIGN_OR_RETURN(slots, fit_slots(slots, p->edge_, p->texel_bytes_ * nch * stored,
                                        ctx.limits().maxImageDimension3D, kMaxAtlasBytes, stored));
  p->slots_ = slots;
  const uint64_t ext[3] = {uint64_t(slots.x) * p->edge_, uint64_t(slots.y) * p->edge_, uint64_t(slots.z) * p->edge_};
  // The ring must hold at least one brick, however wide the container's chunks are.
  const uint64_t staging_bytes = std::max(options.staging_bytes, p->brick_bytes_);
  const VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  // Words where each atlas fits one view and the wide image maps; else the texels as they are.
  const VkExtent3D wide{uint32_t(ext[0] * stored), uint32_t(ext[1]), uint32_t(ext[2])};
  p->words_ = stored > 1 && ext[0] * ext[1] * ext[2] * p->texel_bytes_ * stored <= view_bytes &&
              gpu::host_mapped_image_supported(ctx, VK_IMAGE_TYPE_3D, format, usage, wide);
  VkExtent3D extent{};
  const auto make_atlases = [&]() -> Status {
    extent = p->words_ ? wide : VkExtent3D{uint32_t(ext[0]), uint32_t(ext[1]), uint32_t(ext[2])};
    p->direct_ =
        options.direct_writes && gpu::host_mapped_image_supported(ctx, VK_IMAGE_TYPE_3D, format, usage, extent);
    p->atlases_.clear();
    for (uint32_t c = 0; c < nch; ++c) {
      gpu::ImageCreateInfo ii{VK_IMAGE_TYPE_3D, format, extent, usage, "brick atlas"};
      ii.host_mapped = p->direct_;
      VXR_ASSIGN_OR_RETURN(gpu::Image atlas, gpu::create_image(ctx, ii));
      p->atlases_.push_back(std::move(atlas));
    }
    return Status::ok();
  };
  VXR_RETURN_IF_ERROR(make_atlases());
  // The driver may pad the rows: words only where the padded atlas fits one
  // view as well (a u8 grid of 1 x 20 x 20 slots of 68^3 on lavapipe: 503 MB
  // of words in 592 MB of rows) and its pitches are whole words (the rays
  // index words); otherwise the texels as they are.
  const gpu::Image& first = p->atlases_[0];
  if (p->words_ && (first.depth_pitch * extent.depth > view_bytes || first.row_pitch % 4 != 0 ||
                    first.depth_pitch % 4 != 0)) {
    p->words_ = false;
    VXR_RETURN_IF_ERROR(make_atlases());
  }
  if (p->direct_) {
    // Zeroed by the host (never-written texels are defined), then GENERAL for good.
    for (gpu::Image& atlas : p->atlases_)
      for (uint32_t z = 0; z < extent.depth; ++z)
        for (uint32_t y = 0; y < extent.height; ++y)
          std::memset(atlas.mapped + z * atlas.depth_pitch + y * atlas.row_pitch, 0,
                      size_t(extent.width) * p->texel_bytes_);
    VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
      for (gpu::Image& atlas : p->atlases_)
        gpu::transition_image(cmd, atlas, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT,
                              VK_ACCESS_2_HOST_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                              VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    }));
    p->scratch_.resize(p->brick_bytes_);
    // All atlases or none: the rays read every channel the same way.
    for (const gpu::Image& atlas : p->atlases_) {
      if (!want_views || !p->words_) break;  // texels are read by hand as words only
      Result<gpu::ImageTexels> w = gpu::create_image_texels(ctx, atlas, kAtlasTexelElement);
      if (!w.is_ok()) {
        // Words are only read through views; a sampler would read them as texels.
        if (p->words_) return internal_error("brick pool: texel words without a view: " + w.status().message());
        p->texel_views_.clear();
        break;
      }
      p->texel_views_.push_back(std::move(*w));
    }
  } else {
    VXR_ASSIGN_OR_RETURN(p->staging_, gpu::create_buffer(ctx, {staging_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                               gpu::MemoryIntent::kUpload, "brick staging ring"}));
  }
  // Clear once so never-written texels are defined (validation and determinism).
  if (!p->direct_) VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    for (gpu::Image& atlas : p->atlases_) {
      gpu::transition_image(cmd, atlas, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
      VkClearColorValue zero{};
      VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
      vkCmdClearColorImage(cmd, atlas.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &range);
      gpu::transition_image(cmd, atlas, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                            VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                            VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    }
  }));
  // Slots handed out: no more than the source has bricks, so a small
  // volume's cells can be finer for the same memory.
  const uint32_t usable = uint32_t(std::min<uint64_t>(p->capacity(), bricks));
  p->slot_.resize(usable);
  for (uint32_t i = usable; i-- > 0;) p->free_.push_back(i);
  // The finest cells whose ranges fit kMaxCellRangeBytes: 2 voxels, 4, else 8.
  for (uint32_t voxels : {2u, 4u, 8u}) {
    p->cells_ = brick_cells_for(source.chunk_size(), voxels);
    if (uint64_t(usable) * nch * p->cells_.count() * sizeof(glm::vec2) <= kMaxCellRangeBytes) break;
  }
  const uint64_t cell_bytes = uint64_t(usable) * nch * p->cells_.count() * sizeof(glm::vec2);
  // The renderer's march boxes read them on the host too (kHostShared: cached).
  VXR_ASSIGN_OR_RETURN(p->cell_ranges_, gpu::create_buffer(ctx, {cell_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                                 gpu::MemoryIntent::kHostShared, "brick cell ranges"}));
  // Until a brick is staged its cells are "anything": never skipped.
  auto* cells = static_cast<glm::vec2*>(p->cell_ranges_.mapped);
  for (uint64_t i = 0; i < cell_bytes / sizeof(glm::vec2); ++i) cells[i] = glm::vec2(-INFINITY, INFINITY);
  return p;
}

Status BrickPool::fill_slot(const ChunkKey& key, uint8_t* out) const {
  VXR_ASSIGN_OR_RETURN(bool filled, fill_slot_from(key, out, [this](const ChunkKey& k) { return src_.read(k); }));
  return filled ? Status::ok() : internal_error("brick pool: the source returned no chunk");
}

void BrickPool::slot_chunks(ChunkKey brick, std::vector<ChunkKey>& out) const {
  const LevelInfo& li = src_.levels()[brick.level];
  const bool neighbours = apron_ > src_.apron();
  for (uint32_t c : channel_map_) {
    brick.channel = c;
    if (!neighbours) {
      out.push_back(brick);
      continue;
    }
    // fill_slot_from reads exactly the neighbours that exist (see there).
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int64_t x = int64_t(brick.x) + dx, y = int64_t(brick.y) + dy, z = int64_t(brick.z) + dz;
          if (x < 0 || y < 0 || z < 0 || x >= li.chunk_counts[0] || y >= li.chunk_counts[1] ||
              z >= li.chunk_counts[2])
            continue;
          ChunkKey k = brick;
          k.x = uint32_t(x), k.y = uint32_t(y), k.z = uint32_t(z);
          out.push_back(k);
        }
  }
}

Result<std::shared_ptr<const Chunk>> BrickPool::checked_chunk(const ChunkKey& k, const ReadChunk& fetch) const {
  VXR_ASSIGN_OR_RETURN(auto chunk, fetch(k));
  if (!chunk) return chunk;  // not loaded yet (streaming)
  const DType dtype = src_.info().dtype;
  const uint32_t e = src_.chunk_size() + 2 * src_.apron();
  if (chunk->edge != e || chunk->dtype != dtype || chunk->data.size() != uint64_t(e) * e * e * dtype_bytes(dtype))
    return internal_error("brick pool: chunk level " + std::to_string(k.level) + " has edge " +
                          std::to_string(chunk->edge) + " and " + std::to_string(chunk->data.size()) +
                          " bytes, expected edge " + std::to_string(e) + " of " + dtype_name(dtype));
  return chunk;
}

Result<const uint8_t*> BrickPool::slot_texels_from(const ChunkKey& key, uint8_t* out, const ReadChunk& fetch,
                                                   std::shared_ptr<const Chunk>& keep) const {
  const DType dtype = src_.info().dtype;
  if (apron_ == src_.apron() && (dtype == DType::kU8 || dtype == DType::kU16)) {
    VXR_ASSIGN_OR_RETURN(keep, checked_chunk(key, fetch));
    return keep ? keep->data.data() : nullptr;
  }
  VXR_ASSIGN_OR_RETURN(bool filled, fill_slot_from(key, out, fetch));
  return filled ? out : nullptr;
}

Result<bool> BrickPool::fill_slot_from(const ChunkKey& key, uint8_t* out, const ReadChunk& fetch) const {
  const DType dtype = src_.info().dtype;
  const uint32_t a = src_.apron(), cs = src_.chunk_size();
  auto read = [&](const ChunkKey& k) { return checked_chunk(k, fetch); };
  if (apron_ == a) {  // the payload is the slot
    VXR_ASSIGN_OR_RETURN(auto chunk, read(key));
    if (!chunk) return false;
    convert_to_texels(dtype, chunk->data.data(), size_t(edge_) * edge_ * edge_, out);
    return true;
  }
  // Wider than the source's apron: slot voxel i of an axis is the level's
  // voxel clamp(c * cs - apron_ + i, 0, dims - 1), which lies in this chunk's
  // payload or in a neighbour's (offset -1, 0 or +1: apron_ <= 4 < cs).
  const LevelInfo& li = src_.levels()[key.level];
  const uint32_t c[3] = {key.x, key.y, key.z};
  std::vector<int8_t> nb[3];       // neighbour offset per slot voxel and axis
  std::vector<uint32_t> local[3];  // payload index within that neighbour
  for (int ax = 0; ax < 3; ++ax) {
    nb[ax].resize(edge_);
    local[ax].resize(edge_);
    for (uint32_t i = 0; i < edge_; ++i) {
      const int64_t raw = int64_t(c[ax]) * cs - int64_t(apron_) + i;
      const int64_t own = raw - (int64_t(c[ax]) * cs - int64_t(a));  // index in this chunk's payload
      if (own >= 0 && own < int64_t(cs + 2 * a)) {
        nb[ax][i] = 0;  // the payload already applies the clamp rule
        local[ax][i] = uint32_t(own);
        continue;
      }
      const int64_t g = std::clamp<int64_t>(raw, 0, int64_t(li.dims[ax]) - 1);
      const int64_t n = g / cs;
      nb[ax][i] = int8_t(n - int64_t(c[ax]));
      local[ax][i] = uint32_t(g - n * cs + a);
    }
  }
  // The (up to 27) chunks, converted to texels once each.
  std::vector<uint8_t> texels[27];
  const uint32_t e = cs + 2 * a;
  const size_t payload = size_t(e) * e * e;
  for (uint32_t z = 0; z < edge_; ++z)
    for (uint32_t y = 0; y < edge_; ++y)
      for (uint32_t x = 0; x < edge_; ++x) {
        const int slot = (nb[0][x] + 1) + 3 * (nb[1][y] + 1) + 9 * (nb[2][z] + 1);
        if (texels[slot].empty()) {
          ChunkKey k = key;
          k.x = uint32_t(int64_t(key.x) + nb[0][x]);
          k.y = uint32_t(int64_t(key.y) + nb[1][y]);
          k.z = uint32_t(int64_t(key.z) + nb[2][z]);
          VXR_ASSIGN_OR_RETURN(auto chunk, read(k));
          if (!chunk) return false;
          texels[slot].resize(payload * texel_bytes_);
          convert_to_texels(dtype, chunk->data.data(), payload, texels[slot].data());
        }
        const size_t from = (size_t(local[2][z]) * e + local[1][y]) * e + local[0][x];
        std::memcpy(out + ((size_t(z) * edge_ + y) * edge_ + x) * texel_bytes_,
                    texels[slot].data() + from * texel_bytes_, texel_bytes_);
      }
  return true;
}

glm::uvec3 BrickPool::slot_origin(uint32_t slot) const {
  const uint32_t x = slot % slots_.x, y = (slot / slots_.x) % slots_.y, z = slot / (slots_.x * slots_.y);
  const uint32_t a = apron_;
  return {x * edge_ + a, y * edge_ + a, z * edge_ + a};
}

glm::uvec3 BrickPool::touch(ChunkKey key) {
  key.channel = 0;
  const uint32_t s = map_.at(key);
  slot_[s].last_used = frame_;
  return slot_origin(s);
}

Result<uint32_t> BrickPool::free_slot(UploadStats& stats) {
  if (!free_.empty()) {
    const uint32_t s = free_.back();
    free_.pop_back();
    return s;
  }
  // Least recently used, never one drawn this frame or pinned.
  uint32_t best = UINT32_MAX;
  for (uint32_t i = 0; i < slot_.size(); ++i) {
    const Slot& s = slot_[i];
    if (!s.used || s.pinned || s.last_used >= frame_) continue;
    if (best == UINT32_MAX || s.last_used < slot_[best].last_used) best = i;
  }
  if (best == UINT32_MAX) return out_of_range("brick pool: every slot is in use this frame");
  map_.erase(slot_[best].key);
  slot_[best].used = false;
  ++stats.evicted;
  return best;
}

Result<UploadStats> BrickPool::stage(const std::vector<ChunkKey>& requests, uint64_t budget_bytes,
                                     const ReadChunk& fetch, std::vector<std::vector<VkBufferImageCopy>>& regions) {
  regions.assign(atlases_.size(), {});  // per atlas
  UploadStats st;
  std::vector<DeferredWrite> writes;
  uint64_t ring = 0;
  for (ChunkKey key : requests) {
    key.channel = 0;
    if (resident(key)) continue;
    const bool over_budget = st.bricks > 0 && st.bytes + brick_bytes_ > budget_bytes;
    if (over_budget || (!direct_ && ring + brick_bytes_ > staging_.size)) {
      ++st.deferred;
      continue;
    }
    // Each channel's slot texels: in the staging ring, or (direct writes) the
    // chunk's own bytes where they already are the slot, else the scratch.
    uint8_t* brick = direct_ ? scratch_.data() : static_cast<uint8_t*>(staging_.mapped) + ring;
    const uint8_t* texels[VXR_MAX_CHANNELS] = {};
    std::shared_ptr<const Chunk> keep[VXR_MAX_CHANNELS];
    bool complete = true;
    for (uint32_t c = 0; c < channels() && complete; ++c) {
      ChunkKey ck = key;
      ck.channel = channel_map_[c];
      uint8_t* out = brick + c * channel_bytes_;
      if (direct_) {
        VXR_ASSIGN_OR_RETURN(texels[c], slot_texels_from(ck, out, fetch, keep[c]));
        complete = texels[c] != nullptr;
      } else {
        VXR_ASSIGN_OR_RETURN(complete, fill_slot_from(ck, out, fetch));
        texels[c] = out;
      }
    }
    if (!complete) {  // streaming: a chunk it needs is not decoded yet
      ++st.deferred;
      continue;
    }
    auto slot = free_slot(st);
    if (!slot) {
      ++st.deferred;
      break;
    }
    const glm::uvec3 o = slot_origin(*slot) - glm::uvec3(apron_);
    for (uint32_t c = 0; c < channels() && !direct_; ++c) {
      VkBufferImageCopy r{};
      r.bufferOffset = ring + c * channel_bytes_;
      r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
      r.imageOffset = {int32_t(o.x), int32_t(o.y), int32_t(o.z)};
      r.imageExtent = {edge_, edge_, edge_};
      regions[c].push_back(r);
    }
    for (uint32_t c = 0; c < channels(); ++c) {
      if (direct_ && keep[c]) {
        // The texels are the chunk's own bytes (kept alive here): write them later, in parallel.
        writes.push_back({*slot, c, texels[c], std::move(keep[c])});
      } else {
        write_brick_channel(*slot, c, texels[c]);
      }
    }
    if (!direct_) ring += (brick_bytes_ + 15) & ~uint64_t(15);
    slot_[*slot] = {key, frame_, false, true};
    map_[key] = *slot;
    ++st.bricks;
    st.bytes += brick_bytes_;
  }
  write_in_parallel(writes);
  return st;
}

void BrickPool::write_brick_channel(uint32_t slot, uint32_t c, const uint8_t* texels) {
  compute_cell_ranges(atlases_[0].format, texels, src_.chunk_size(), apron_, cells_,
                      static_cast<glm::vec2*>(cell_ranges_.mapped) + (size_t(slot) * channels() + c) * cells_.count());
  if (direct_) write_slot(c, slot, texels);
}

void BrickPool::write_in_parallel(const std::vector<DeferredWrite>& writes) {
  // Slots are disjoint, so bricks are written (and their cells computed) by
  // up to hardware_concurrency threads; the calling thread takes a share.
  // On lavapipe this copy and the cell scan were most of a movie's upload.
  const size_t threads = std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), writes.size() / 8 + 1);
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < writes.size();)
      write_brick_channel(writes[i].slot, writes[i].channel, writes[i].texels);
  };
  std::vector<std::thread> helpers;
  for (size_t t = 1; t < threads; ++t) helpers.emplace_back(work);
  work();
  for (auto& h : helpers) h.join();
}

void BrickPool::write_slot(uint32_t c, uint32_t slot, const uint8_t* texels) {
  // The slot is not drawn this frame (free_slot) and the caller waited for the
  // frames that drew it, so nothing on the device reads these texels now.
  const gpu::Image& atlas = atlases_[c];
  const glm::uvec3 o = slot_origin(slot) - glm::uvec3(apron_);
  const size_t row = size_t(edge_) * texel_bytes_, stored = words_ ? texel_word_width(atlas.format) : 1;
  for (uint32_t z = 0; z < edge_; ++z)
    for (uint32_t y = 0; y < edge_; ++y) {
      uint8_t* to = atlas.mapped + (o.z + z) * atlas.depth_pitch + (o.y + y) * atlas.row_pitch +
                    size_t(o.x) * texel_bytes_ * stored;
      const uint8_t* from = texels + (size_t(z) * edge_ + y) * row;
      if (words_) write_texel_words(atlas.format, from, y + 1 < edge_ ? from + row : from, edge_, to);
      else std::memcpy(to, from, row);
    }
}

void BrickPool::record_copies(VkCommandBuffer cmd, const std::vector<std::vector<VkBufferImageCopy>>& regions) {
  if (direct_) return;  // written in place by stage()
  for (uint32_t c = 0; c < channels(); ++c) {
    gpu::Image& atlas = atlases_[c];
    gpu::transition_image(cmd, atlas, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                          VK_ACCESS_2_TRANSFER_WRITE_BIT);
    vkCmdCopyBufferToImage(cmd, staging_.buffer, atlas.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                           static_cast<uint32_t>(regions[c].size()), regions[c].data());
    gpu::transition_image(cmd, atlas, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
                          VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
}

Result<UploadStats> BrickPool::upload(const std::vector<ChunkKey>& requests, uint64_t budget_bytes) {
  VXR_TRACE_SCOPE("brick_pool.upload");
  std::vector<std::vector<VkBufferImageCopy>> regions;
  VXR_ASSIGN_OR_RETURN(UploadStats st,
                       stage(requests, budget_bytes, [this](const ChunkKey& k) { return src_.read(k); }, regions));
  if (st.bricks == 0 || direct_) return st;
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) { record_copies(cmd, regions); }));
  return st;
}

Result<UploadStats> BrickPool::record_upload(VkCommandBuffer cmd, const std::vector<ChunkKey>& requests,
                                             uint64_t budget_bytes, const Fetch& fetch) {
  VXR_TRACE_SCOPE("brick_pool.record_upload");
  std::vector<std::vector<VkBufferImageCopy>> regions;
  VXR_ASSIGN_OR_RETURN(UploadStats st, stage(requests, budget_bytes,
                                             [&](const ChunkKey& k) -> Result<std::shared_ptr<const Chunk>> {
                                               return fetch(k);
                                             },
                                             regions));
  if (st.bricks > 0) record_copies(cmd, regions);
  return st;
}

Status BrickPool::pin_top_level(uint32_t timepoint) {
  if (timepoint >= src_.info().timepoints)
    return invalid_argument("brick pool: timepoint " + std::to_string(timepoint) + " asked for, the volume has " +
                            std::to_string(src_.info().timepoints));
  const uint32_t top = static_cast<uint32_t>(src_.levels().size()) - 1;
  const auto& li = src_.levels()[top];
  std::vector<ChunkKey> keys;
  for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
    for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
      for (uint32_t x = 0; x < li.chunk_counts[0]; ++x) keys.push_back({top, x, y, z, 0, timepoint});
  if (keys.size() > capacity() / 2)
    return out_of_range("brick pool: the top level has " + std::to_string(keys.size()) +
                        " chunks, too many to pin in " + std::to_string(capacity()) + " slots");
  for (Slot& s : slot_) s.pinned = false;  // another timepoint's pins become ordinary bricks
  return pin(keys);
}

Status BrickPool::pin(const std::vector<ChunkKey>& keys) {
  if (keys.size() > capacity() / 2)
    return out_of_range("brick pool: " + std::to_string(keys.size()) + " chunks are too many to pin in " +
                        std::to_string(capacity()) + " slots");
  while (true) {
    VXR_ASSIGN_OR_RETURN(UploadStats st, upload(keys, UINT64_MAX));
    if (st.deferred == 0) break;
    if (st.bricks == 0) return out_of_range("brick pool: no room to pin " + std::to_string(keys.size()) + " chunks");
  }
  for (const ChunkKey& k : keys) slot_[map_.at(k)].pinned = true;
  return Status::ok();
}

}  // namespace vxr

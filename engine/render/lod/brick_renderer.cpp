#include "render/lod/brick_renderer.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>

#include "core/trace.h"
#include "render/raycast_setup.h"
#include "shared/brick_params.h"
#include "shared/raycast_params.h"

namespace vxr {
namespace {

std::vector<VkDescriptorSetLayoutBinding> bindings() {
  return {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VXR_MAX_CHANNELS, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // one atlas per channel
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // transfer table
      {2, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {3, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {5, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {7, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {8, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // cell ranges
      {9, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},   // underlay depth
      {10, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // underlay colour
      {11, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // cell keys
      {12, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // transfer rows
      {13, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // cell bits
      {14, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // cell bits' window
      {15, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // brick records as texels
      {16, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // cell keys as texels
      {17, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, VXR_MAX_CHANNELS, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // atlas texel views
      {18, VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},  // work items as texels
  };
}

// The cells a ray walks. E-A and emission: the pool's. MIP / MinIP test a
// cell against the ray's running value, one cell per walk, so finer cells
// cost more walks than they save samples (MRI MIP at step 0.5: 118 ms with
// 2-voxel cells, 102 with 4): they walk cells of at least 4 voxels, 2x2x2 of
// the pool's 2-voxel ones, keyed from the union of their ranges.
BrickCells walk_cells(const BrickCells& pool, bool reduce) {
  if (!reduce || pool.cell_size >= 4) return pool;
  return {(pool.cells_per_axis + 1) / 2, pool.cell_size * 2};
}

// One brick record's emptiness bits (brick_raycast.comp cell_words()) for walked cells `walk`.
uint64_t cell_bits_bytes(const BrickCells& walk) { return (walk.count() + 31) / 32 * 4; }

glm::vec4 v4(const glm::dvec3& v, double w = 0.0) {
  return glm::vec4(static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z), static_cast<float>(w));
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void compute_barrier(VkCommandBuffer cmd) {
  // Uniform and sampled reads too: the rays read the classify pass's bits
  // through a uniform window and its keys as texels.
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                      VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                          VK_ACCESS_2_UNIFORM_READ_BIT | VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

// One barrier that orders everything before it against compute work after it:
// views of a frame share the accumulation image and the atlas.
void full_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                      dst_stage, dst_access);
}

constexpr uint64_t kSampleCounterBytes = uint64_t(VXR_SAMPLE_COUNTERS) * VXR_SAMPLE_COUNTER_STRIDE * 4;

// The samples the rays counted (brick_raycast.comp, VXR_SAMPLE_COUNTERS).
uint64_t sum_sample_counters(const void* mapped) {
  uint64_t sum = 0;
  for (uint32_t i = 0; i < VXR_SAMPLE_COUNTERS; ++i) {
    uint32_t c[2];
    std::memcpy(c, static_cast<const char*>(mapped) + i * VXR_SAMPLE_COUNTER_STRIDE * 4, sizeof(c));
    sum += uint64_t(c[0]) | (uint64_t(c[1]) << 32);
  }
  return sum;
}

// Clears `image` (GENERAL layout) to `color` after every command recorded
// before, for the compute shaders recorded after.
void clear_image(VkCommandBuffer cmd, VkImage image, const VkClearColorValue& color) {
  full_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, image, VK_IMAGE_LAYOUT_GENERAL, &color, 1, &range);
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
}

VkDeviceSize align_up(VkDeviceSize v, VkDeviceSize a) { return a > 1 ? (v + a - 1) / a * a : v; }

}  // namespace

bool is_unorm8(VkFormat f) {
  switch (f) {
    case VK_FORMAT_R8G8B8A8_UNORM:
    case VK_FORMAT_B8G8R8A8_UNORM:
    case VK_FORMAT_A8B8G8R8_UNORM_PACK32: return true;
    default: return false;
  }
}

std::string format_stats(const BrickFrameStats& s) {
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "visited %llu drawn %llu (fallback %llu) empty %llu culled %llu missing %llu samples %llu "
                "uploaded %u bricks %.2f MiB hit %.1f%% traverse %.2f ms render %.2f ms; cells walked in %u bricks; "
                "tile entries %u from %u blocks, tiles without walks %u, without bricks %u%s",
                (unsigned long long)s.lod.visited, (unsigned long long)s.lod.drawn,
                (unsigned long long)s.lod.fallback, (unsigned long long)s.lod.skipped_empty,
                (unsigned long long)s.lod.culled, (unsigned long long)s.lod.missing, (unsigned long long)s.samples,
                s.bricks_uploaded, double(s.bytes_uploaded) / (1 << 20), 100.0 * s.hit_rate, s.traverse_ms,
                s.render_ms, s.bricks_walked, s.tile_entries, s.tile_blocks, s.tiles_plain, s.tiles_empty,
                s.hue_lookups ? "; colours from single-hue rows" : "");
  return buf;
}

Status check_brick_settings(const RenderSettings& s, uint32_t channels) {
  if (s.channels.empty()) return invalid_argument("render settings: no channel settings");
  return validate_render_settings(s, channels);
}

namespace {
double windowed(const ChannelSettings& c, double v) {
  const double x = std::clamp((v - c.window_lo) / (c.window_hi - c.window_lo), 0.0, 1.0);
  return c.gamma == 1.0 ? x : std::pow(x, c.gamma);
}

// The iso value windowed as plan_raycast gives it to the rays, and whether
// windowed value x lies clearly below it (by far more than float rounding).
double iso_windowed(const RenderSettings& s) { return windowed(channel_settings(s, s.iso_channel), s.iso_value); }
bool clearly_below(double x, double iso_norm) { return x < iso_norm - 1e-4; }

// Average: whether every value up to `max` (data units) windows to 0
// exactly (brick_raycast.comp average_cell_clear: the same rule). Filters
// weigh voxels by non-negative weights, so voxels at or below 0 filter to
// at most 0, which a window starting at or above 0 clamps to 0; any other
// maximum must lie clearly below the window's low end, by far more than a
// filter's rounding.
bool average_clear(bool none_above_0, double max, double lo, double hi) {
  return (none_above_0 && lo >= 0.0) || (max - lo) / (hi - lo) < -1e-4;
}
}  // namespace

bool iso_back_sample(const RenderSettings& s) {
  return s.model == OpticalModel::kIsosurface && s.step_voxels <= kIsoBackStep;
}

bool average_shows_zero(const RenderSettings& s, const TransferTable& table) {
  for (size_t c = 0; c < s.channels.size() && c < VXR_MAX_CHANNELS; ++c)
    if (s.channels[c].enabled && table.at(int(c), 0).a > 0.0) return true;
  return false;
}

bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, std::span<const ChunkStats> ranges) {
  // Iso tests its channel; the others each enabled channel.
  if (s.model == OpticalModel::kAverage) {
    if (average_shows_zero(s, table)) return true;
    for (size_t c = 0; c < ranges.size() && c < s.channels.size(); ++c) {
      const ChannelSettings& ch = s.channels[c];
      if (ch.enabled && !average_clear(ranges[c].max <= 0.0, ranges[c].max, ch.window_lo, ch.window_hi)) return true;
    }
    return false;
  }
  if (s.model == OpticalModel::kIsosurface) {
    if (!iso_back_sample(s) || s.iso_channel >= ranges.size() || s.iso_channel >= s.channels.size()) return true;
    const ChannelSettings& ch = s.channels[s.iso_channel];
    return !ch.enabled ? !clearly_below(0.0, iso_windowed(s))  // the rays see a channel not drawn as 0
                       : !clearly_below(windowed(ch, ranges[s.iso_channel].max), iso_windowed(s));
  }
  const int n = VXR_TF_SIZE - 1;
  for (size_t c = 0; c < ranges.size() && c < s.channels.size(); ++c) {
    const ChannelSettings& ch = s.channels[c];
    if (!ch.enabled) continue;
    const double x0 = windowed(ch, ranges[c].min), x1 = windowed(ch, ranges[c].max);  // monotonic
    if (s.model == OpticalModel::kMip) {
      if (x1 > 0.0 || table.at(int(c), 0).a > 0.0) return true;
    } else if (s.model == OpticalModel::kMinIp) {
      if (x0 < 1.0 || table.at(int(c), n).a > 0.0) return true;
    } else {
      // vxr_transfer_table mixes entries floor(u) and floor(u) + 1, u = x * 255.
      const int i0 = std::clamp(int(std::floor(x0 * n)), 0, n), i1 = std::clamp(int(std::ceil(x1 * n)), 0, n);
      for (int i = i0; i <= i1; ++i)
        if (table.at(int(c), i).a > 0.0) return true;
    }
  }
  return false;
}

bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, double lo, double hi) {
  const ChunkStats r{lo, hi};
  return brick_may_contribute(s, table, std::span(&r, 1));
}

namespace {
// Per entry i of a channel's table: how many of entries 0..i have non-zero
// opacity (any entry in i0..i1 is opaque when upto[i1] - upto[i0 - 1] > 0).
std::array<uint16_t, VXR_TF_SIZE> opaque_entries_upto(const TransferTable& table, int channel) {
  std::array<uint16_t, VXR_TF_SIZE> upto{};
  uint16_t n = 0;
  for (int i = 0; i < VXR_TF_SIZE; ++i) upto[i] = n += table.at(channel, i).a != 0.0 ? 1 : 0;
  return upto;
}
}  // namespace

CellOpacity::CellOpacity(const RenderSettings& s, const TransferTable& table, const std::vector<double>& value_scales) {
  uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a over what the test reads
  auto mix = [&h](const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 0x100000001b3ull;
  };
  model_ = s.model;
  mix(&model_, sizeof(model_));
  whole_bricks_ = s.model == OpticalModel::kAverage && average_shows_zero(s, table);
  mix(&whole_bricks_, sizeof(whole_bricks_));
  if (iso_back_sample(s)) {
    iso_skips_ = true;
    iso_channel_ = s.iso_channel;
    iso_norm_ = iso_windowed(s);
    mix(&iso_channel_, sizeof(iso_channel_));
    mix(&iso_norm_, sizeof(iso_norm_));
  }
  for (size_t c = 0; c < value_scales.size(); ++c) {
    Channel ch;
    if (c < s.channels.size()) {
      const ChannelSettings& cs = s.channels[c];
      ch.enabled = cs.enabled;
      ch.lo = cs.window_lo, ch.hi = cs.window_hi, ch.gamma = cs.gamma;
    }
    ch.scale = value_scales[c];
    ch.opaque_upto = opaque_entries_upto(table, int(c));
    mix(&ch.enabled, sizeof(ch.enabled));
    for (double v : {ch.lo, ch.hi, ch.gamma, ch.scale}) mix(&v, sizeof(v));
    mix(ch.opaque_upto.data(), ch.opaque_upto.size() * sizeof(uint16_t));
    channels_.push_back(std::move(ch));
  }
  hash_ = h ? h : 1;
}

double CellOpacity::windowed(uint32_t channel, double texel) const {
  const Channel& ch = channels_[channel];
  if (!ch.enabled) return 0.0;
  const double x = std::clamp((texel * ch.scale - ch.lo) / (ch.hi - ch.lo), 0.0, 1.0);
  return ch.gamma == 1.0 ? x : std::pow(x, ch.gamma);
}

bool CellOpacity::may_contribute(uint32_t channel, glm::vec2 texel_range) const {
  const Channel& ch = channels_[channel];
  if (model_ == OpticalModel::kIsosurface) {
    // Only the iso channel's crossings end a ray; a cell it is clearly below holds none.
    if (!iso_skips_) return true;
    return channel == iso_channel_ && !clearly_below(windowed(channel, texel_range.y), iso_norm_);
  }
  if (!ch.enabled) return false;
  // Average sums windowed values: a cell adds nothing when each of its
  // samples windows to 0 exactly. A stored maximum within the pool's
  // padding of 0 means no voxel above 0.
  if (model_ == OpticalModel::kAverage)
    return !average_clear(texel_range.y <= float(VXR_CELL_PAD_ABS), texel_range.y * ch.scale, ch.lo, ch.hi);
  // The lookup at u = x * 255 mixes entries floor(u) and floor(u) + 1 (the
  // latter with weight 0 at an integer u). The shader's float u lies within
  // far less than kSlack of this one; a value clear of the window (by more
  // than float error) is clamped to 0 or 1 exactly there too and reaches one entry.
  const int n = VXR_TF_SIZE - 1;
  constexpr double kClear = 1e-6, kSlack = 1e-3;
  auto entry = [&ch, n](double texel, bool upper) {
    double x = (texel * ch.scale - ch.lo) / (ch.hi - ch.lo);
    if (x <= -kClear) return 0;
    if (x >= 1.0 + kClear) return n;
    x = std::clamp(x, 0.0, 1.0);
    const double u = (ch.gamma == 1.0 ? x : std::pow(x, ch.gamma)) * n;
    return std::clamp(int(upper ? std::ceil(u + kSlack) : std::floor(u - kSlack)), 0, n);
  };
  // MIP: a cell clearly below the window (windowed 0) never raises a running
  // maximum, and a ray that takes nothing shows entry 0; MinIP the mirror.
  if (model_ == OpticalModel::kMip) return entry(texel_range.y, true) > 0 || ch.opaque_upto[0] > 0;
  if (model_ == OpticalModel::kMinIp)
    return entry(texel_range.x, false) < n || ch.opaque_upto[n] - ch.opaque_upto[n - 1] > 0;
  if (model_ != OpticalModel::kEmissionAbsorption && model_ != OpticalModel::kEmission) return true;
  const int i0 = entry(texel_range.x, false), i1 = entry(texel_range.y, true);
  return ch.opaque_upto[i1] - (i0 > 0 ? ch.opaque_upto[i0 - 1] : 0) > 0;
}

bool brick_state_fits_texel(const RenderSettings& s, uint32_t channels) {
  switch (s.model) {
    case OpticalModel::kEmissionAbsorption: return channels == 1 || s.blend == ChannelBlend::kComposite;
    case OpticalModel::kEmission:
    case OpticalModel::kIsosurface: return true;
    case OpticalModel::kMip:
    case OpticalModel::kMinIp: return channels == 1;
    case OpticalModel::kAverage: return channels <= 3;
  }
  return false;
}

Result<std::unique_ptr<BrickRenderer>> BrickRenderer::create(gpu::Context& ctx, const ChunkSource& source,
                                                             const BrickRendererOptions& options) {
  std::unique_ptr<BrickRenderer> r(new BrickRenderer(ctx, source));
  r->opt_ = options;
  if (source.apron() < 1) return invalid_argument("brick renderer: chunks need an apron of at least 1 voxel");
  VXR_ASSIGN_OR_RETURN(r->pool_, BrickPool::create(ctx, source, options.pool));
  r->value_scales_.assign(r->pool_->channels(), brick_value_scale(source.info().dtype));
  const auto b = bindings();
  r->pipes_ = options.pipelines ? options.pipelines : std::make_shared<BrickPipelines>();
  VXR_ASSIGN_OR_RETURN(r->pipeline_, r->variant({.cells = true, .fast = {true, true}}));
  if (options.max_views == 0) return invalid_argument("brick renderer: max_views must be at least 1");
  VXR_ASSIGN_OR_RETURN(r->desc_pool_, gpu::create_descriptor_pool(ctx, b, options.max_views + 1));
  VXR_ASSIGN_OR_RETURN(r->mono_set_, gpu::allocate_descriptor_set(ctx, r->desc_pool_, r->pipeline_->set_layout));
  for (uint32_t i = 0; i < options.max_views; ++i) {
    VXR_ASSIGN_OR_RETURN(VkDescriptorSet set, gpu::allocate_descriptor_set(ctx, r->desc_pool_, r->pipeline_->set_layout));
    r->view_sets_.push_back(set);
  }
  VXR_ASSIGN_OR_RETURN(r->linear_, gpu::create_linear_clamp_sampler(ctx));
  // A buffer, not a texture: on lavapipe a texelFetch from an image runs the
  // sampler's code. The rays read the colour and opacity rows through a
  // storage texel view (binding 12): lavapipe loads a ray's texel whole,
  // inline, where a storage buffer loads ray by ray with a branch each and
  // a uniform buffer at per-ray offsets component by component
  // (docs/skipping-perf.md, fifth and seventh rounds).
  const uint64_t tf_bytes = uint64_t(VXR_TF_SIZE) * VXR_TF_ROWS * sizeof(glm::vec4);
  VXR_ASSIGN_OR_RETURN(r->transfer_buf_,
                       gpu::create_buffer(ctx, {tf_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                                              VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT |
                                                              VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                gpu::MemoryIntent::kDeviceLocal, "transfer function"}));
  VXR_ASSIGN_OR_RETURN(r->transfer_rows_, gpu::create_buffer_view(ctx, r->transfer_buf_.buffer,
                                                                   VK_FORMAT_R32G32B32A32_SFLOAT, 0, tf_bytes));
  VXR_ASSIGN_OR_RETURN(r->tf_staging_, gpu::create_buffer(ctx, {tf_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                                gpu::MemoryIntent::kUpload, "transfer function staging"}));
  VXR_ASSIGN_OR_RETURN(r->table_, gpu::create_buffer(ctx, {uint64_t(options.max_bricks) * sizeof(shader::BrickRecord),
                                                           VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                                               VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT,
                                                           gpu::MemoryIntent::kUpload, "brick table"}));
  // The table as RGBA32F texels for the rays (binding 15): all of it where
  // the device's texel buffers hold it (FastReads::record_texels), else
  // a stand-in over its start that no ray reads.
  const uint64_t table_texels = r->table_.size / sizeof(glm::vec4);
  r->table_texels_fit_ = table_texels <= ctx.limits().maxTexelBufferElements;
  VXR_ASSIGN_OR_RETURN(r->table_texels_,
                       gpu::create_buffer_view(ctx, r->table_.buffer, VK_FORMAT_R32G32B32A32_SFLOAT, 0,
                                               r->table_texels_fit_ ? r->table_.size : sizeof(glm::vec4)));
  VXR_ASSIGN_OR_RETURN(r->counters_, gpu::create_buffer(ctx, {kSampleCounterBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                              gpu::MemoryIntent::kReadback, "brick counters"}));
  VXR_ASSIGN_OR_RETURN(r->items_, gpu::create_buffer(ctx, {uint64_t(options.max_work_items) * sizeof(glm::uvec4),
                                                           kWorkListUsage, gpu::MemoryIntent::kUpload,
                                                           "brick work items"}));
  VXR_RETURN_IF_ERROR(r->make_item_texels());
  if (ctx.timestamp_period_ns() > 0.0) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 2;
    VkQueryPool qp = VK_NULL_HANDLE;
    if (VkResult vr = vkCreateQueryPool(ctx.device(), &qi, nullptr, &qp); vr != VK_SUCCESS)
      return internal_error("brick renderer: vkCreateQueryPool failed (" + std::to_string(int(vr)) + ")");
    r->timestamps_ = gpu::Handle<VkQueryPool>(ctx.device(), qp);
  }
  r->params_stride_ = align_up(sizeof(shader::RaycastParams), ctx.limits().minUniformBufferOffsetAlignment);
  VXR_ASSIGN_OR_RETURN(r->params_, gpu::create_buffer(ctx, {r->params_stride_ * options.max_views,
                                                            VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                                            gpu::MemoryIntent::kUpload, "brick raycast params"}));
  // A view without an underlay still binds one (the flag says not to read it).
  for (auto [img, format, name] : {std::tuple{&r->no_under_depth_, VK_FORMAT_R32_SFLOAT, "no underlay depth"},
                                   std::tuple{&r->no_under_color_, VK_FORMAT_R8G8B8A8_UNORM, "no underlay colour"}}) {
    VXR_ASSIGN_OR_RETURN(*img, gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, format, {1, 1, 1}, VK_IMAGE_USAGE_STORAGE_BIT, name}));
  }
  VXR_RETURN_IF_ERROR(ctx.submit_and_wait([&](VkCommandBuffer cmd) {
    for (gpu::Image* img : {&r->no_under_depth_, &r->no_under_color_})
      gpu::transition_image(cmd, *img, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  }));
  VXR_ASSIGN_OR_RETURN(r->no_texels_buf_, gpu::create_buffer(ctx, {16, VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT,
                                                                    gpu::MemoryIntent::kDeviceLocal, "no atlas texels"}));
  VXR_ASSIGN_OR_RETURN(r->no_texels_, gpu::create_buffer_view(ctx, r->no_texels_buf_.buffer, kAtlasTexelElement, 0, 16));
  std::vector<VkDescriptorSet> all = r->view_sets_;
  all.push_back(r->mono_set_);
  VXR_RETURN_IF_ERROR(r->ensure_cell_keys());
  for (VkDescriptorSet set : all) {
    gpu::write_storage_image(ctx, set, 9, r->no_under_depth_.view);
    gpu::write_storage_image(ctx, set, 10, r->no_under_color_.view);
    if (set != r->mono_set_) r->bind_atlases(set, r->pool_atlases());
    else r->bind_atlases(set, {});  // the texel views' stand-ins until set_monolithic
    // The monolithic texture has no cells (its record says so); the binding still needs a buffer.
    gpu::write_storage_buffer(ctx, set, 8, r->pool_->cell_ranges().buffer);
    gpu::write_storage_buffer(ctx, set, 5, r->counters_.buffer);
    gpu::write_storage_buffer(ctx, set, 1, r->transfer_buf_.buffer);
    gpu::write_storage_texel_buffer(ctx, set, 12, r->transfer_rows_.get());
    gpu::write_storage_texel_buffer(ctx, set, 15, r->table_texels_.get());
  }
  gpu::write_storage_buffer(ctx, r->mono_set_, 4, r->table_.buffer);
  gpu::write_storage_buffer(ctx, r->mono_set_, 6, r->items_.buffer);
  gpu::write_storage_texel_buffer(ctx, r->mono_set_, 18, r->item_texels_.get());
  gpu::write_uniform_buffer(ctx, r->mono_set_, 7, r->params_.buffer, sizeof(shader::RaycastParams));
  VXR_RETURN_IF_ERROR(r->ensure_target(1, 1));  // the storage binding needs an image even when views blit
  VXR_RETURN_IF_ERROR(r->pin_resident(0));
  return r;
}

Status BrickRenderer::ensure_cell_keys() {
  const uint64_t key_bytes =
      uint64_t(pool_->capacity()) * pool_->channels() * walk_cells(pool_->cells(), true).count() * sizeof(float);
  // The finest walk's bits for every record of a frame, each view's region aligned for its descriptors.
  const uint64_t bit_bytes =
      uint64_t(opt_.max_bricks) * cell_bits_bytes(pool_->cells()) + uint64_t(opt_.max_views) * cell_bits_align();
  // Written by a view's classify pass before its rays read them; never read elsewhere.
  classified_.assign(opt_.max_views, std::nullopt);  // a new pool's ranges, or new buffers
  if (!cell_keys_.buffer || cell_keys_.size != key_bytes) {
    cell_key_texels_ = {};  // the view goes before its buffer
    VXR_ASSIGN_OR_RETURN(cell_keys_, gpu::create_buffer(ctx_, {key_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                                                              VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT,
                                                               gpu::MemoryIntent::kDeviceLocal, "brick cell keys"}));
    // A device with fewer texels than keys reads them from the storage buffer (FastReads::key_texels).
    const uint64_t texels = std::min<uint64_t>(key_bytes / sizeof(float), ctx_.limits().maxTexelBufferElements);
    VXR_ASSIGN_OR_RETURN(cell_key_texels_, gpu::create_buffer_view(ctx_, cell_keys_.buffer, VK_FORMAT_R32_SFLOAT, 0,
                                                                   texels * sizeof(float)));
  }
  if (!cell_bits_.buffer || cell_bits_.size != bit_bytes) {
    VXR_ASSIGN_OR_RETURN(cell_bits_, gpu::create_buffer(ctx_, {bit_bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                                                              VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                                               gpu::MemoryIntent::kDeviceLocal, "brick cell bits"}));
  }
  std::vector<VkDescriptorSet> all = view_sets_;
  all.push_back(mono_set_);
  for (VkDescriptorSet set : all) {
    gpu::write_storage_buffer(ctx_, set, 11, cell_keys_.buffer);
    gpu::write_storage_texel_buffer(ctx_, set, 16, cell_key_texels_.get());
    gpu::write_storage_buffer(ctx_, set, 13, cell_bits_.buffer);
    gpu::write_uniform_buffer(ctx_, set, 14, cell_bits_.buffer, cell_bits_window_bytes(0));
  }
  return Status::ok();
}

uint64_t BrickRenderer::window_bytes(uint64_t declared, const gpu::Buffer& buffer, uint64_t offset) const {
  return std::min<uint64_t>(
      {declared, ctx_.limits().maxUniformBufferRange, buffer.size - std::min<uint64_t>(offset, buffer.size)});
}

uint64_t BrickRenderer::cell_bits_window_bytes(uint64_t offset) const {
  return window_bytes(uint64_t(VXR_CELL_BITS_WINDOW_WORDS) * 4, cell_bits_, offset);
}

uint64_t BrickRenderer::cell_bits_align() const {
  return std::max<uint64_t>({16, ctx_.limits().minStorageBufferOffsetAlignment,
                             ctx_.limits().minUniformBufferOffsetAlignment});
}

void BrickRenderer::forget_overwritten(uint32_t view, const CellClassInputs& written) {
  for (uint32_t v = 0; v < classified_.size(); ++v) {
    std::optional<CellClassInputs>& other = classified_[v];
    if (v == view || !other) continue;
    const bool keys_differ = written.writes_keys() && other->writes_keys() && !written.same_keys(*other);
    const bool bits_meet = !written.writes_keys() && !other->writes_keys() &&
                           written.bits_offset < other->bits_offset + other->bits_bytes &&
                           other->bits_offset < written.bits_offset + written.bits_bytes;
    if (keys_differ || bits_meet) other.reset();
  }
}

Status BrickRenderer::pin_resident(uint32_t timepoint) {
  VXR_RETURN_IF_ERROR(pool_->pin_top_level(timepoint));
  if (!opt_.preload_if_fits) return Status::ok();
  std::vector<ChunkKey> keys;
  for (uint32_t l = 0; l < src_.levels().size(); ++l) {
    const LevelInfo& li = src_.levels()[l];
    for (uint32_t z = 0; z < li.chunk_counts[2]; ++z)
      for (uint32_t y = 0; y < li.chunk_counts[1]; ++y)
        for (uint32_t x = 0; x < li.chunk_counts[0] && keys.size() <= pool_->capacity() / 2; ++x)
          keys.push_back({l, x, y, z, 0, timepoint});
  }
  if (keys.size() <= pool_->capacity() / 2) VXR_RETURN_IF_ERROR(pool_->pin(keys));
  return Status::ok();
}

VolumePlacement BrickRenderer::placement() const {
  const VolumeInfo& info = src_.info();
  return {{uint32_t(info.dims[0]), uint32_t(info.dims[1]), uint32_t(info.dims[2])}, info.voxel_size};
}

LodView BrickRenderer::view_for(const Camera& camera, uint32_t width, uint32_t height) const {
  const VoxelSpaceRays rays = rays_in_voxel_space(camera, placement(), width, height);
  return {rays.eye, rays.forward, rays.right, rays.up, width, height};
}

Status BrickRenderer::ensure_target(uint32_t width, uint32_t height) {
  if (target_.image && target_.extent.width == width && target_.extent.height == height) return Status::ok();
  if (target_.image) retired_.push_back(std::move(target_));
  VXR_ASSIGN_OR_RETURN(target_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM,
                                                         {width, height, 1},
                                                         VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                             VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                         "brick raycast target"}));
  return ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, target_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  });
}

Status BrickRenderer::ensure_accum(uint32_t width, uint32_t height) {
  if (accum_.image && accum_.extent.width >= width && accum_.extent.height >= height) return Status::ok();
  const uint32_t w = std::max(width, accum_.extent.width), h = std::max(height, accum_.extent.height);
  if (accum_.image) retired_.push_back(std::move(accum_));
  VXR_ASSIGN_OR_RETURN(accum_, gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT, {w, h, 1},
                                                        VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                            VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                                        "brick raycast accumulation"}));
  // Created at the first frame (or a larger view); the frames after reuse it.
  return ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, accum_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  });
}

Status BrickRenderer::record_transfer(VkCommandBuffer cmd, const TransferTable& table) {
  if (table.rgba == tf_uploaded_) return Status::ok();
  if (tf_recorded_)
    return invalid_argument("record_view: the views of one frame must share one transfer function "
                            "(same colormap, window and opacity settings)");
  if (table.rgba.size() != size_t(VXR_TF_SIZE) * VXR_MAX_CHANNELS ||
      tf_staging_.size != uint64_t(VXR_TF_SIZE) * VXR_TF_ROWS * sizeof(glm::vec4))
    return internal_error("transfer table has an unexpected size");
  // The rows of shared/brick_params.h (VXR_TF_ROWS).
  auto* rows = static_cast<glm::vec4*>(tf_staging_.mapped);
  std::memcpy(rows, table.rgba.data(), table.rgba.size() * sizeof(glm::vec4));
  for (int c = 0; c < VXR_MAX_CHANNELS; ++c) {
    // How many entries 0..i have non-zero opacity: the cell test asks "is
    // any entry in i0..i1 opaque" in two fetches.
    glm::vec4* counts = rows + size_t(VXR_TF_OPAQUE_ROWS + c) * VXR_TF_SIZE;
    const auto upto = opaque_entries_upto(table, c);
    for (int i = 0; i < VXR_TF_SIZE; ++i) counts[i] = glm::vec4(float(upto[i]), 0.0f, 0.0f, 0.0f);
    glm::vec4* pairs = rows + size_t(VXR_TF_HUE_ROWS + c) * VXR_TF_SIZE;
    const glm::vec4* entry = &table.rgba[size_t(c) * VXR_TF_SIZE];
    const std::optional<glm::vec3>& hue = table.hue[c];
    for (int i = 0; i + 1 < VXR_TF_SIZE; ++i)
      pairs[i] = hue ? glm::vec4(hue_value(*hue, entry[i]), entry[i].a, hue_value(*hue, entry[i + 1]), entry[i + 1].a)
                     : glm::vec4(0.0f);
    pairs[VXR_TF_SIZE - 1] = glm::vec4(hue.value_or(glm::vec3(0.0f)), 0.0f);
  }
  tf_hues_ = table.hue;
  // The previous frame's rays may still read the table; this frame's read it after the copy.
  const VkAccessFlags2 reads = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_UNIFORM_READ_BIT;
  gpu::buffer_barrier(cmd, transfer_buf_.buffer, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, reads,
                 VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
  const VkBufferCopy region{0, 0, tf_staging_.size};
  vkCmdCopyBuffer(cmd, tf_staging_.buffer, transfer_buf_.buffer, 1, &region);
  gpu::buffer_barrier(cmd, transfer_buf_.buffer, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, reads);
  tf_uploaded_ = table.rgba;
  tf_recorded_ = true;
  return Status::ok();
}

namespace {
// Some drawn channel has a gamma other than 1 (constant 104).
bool any_gamma(const RenderSettings& s, uint32_t channels) {
  for (uint32_t c = 0; c < channels && c < s.channels.size(); ++c)
    if (s.channels[c].gamma != 1.0) return true;
  return false;
}
}  // namespace

Result<const gpu::ComputePipeline*> BrickRenderer::pipeline_for(const RenderSettings& s, uint32_t model,
                                                                uint32_t texel_bytes, bool cells, FastReads fast,
                                                                SampleWork work, bool waves, bool no_bricks) {
  ShaderVariant v{.model = model, .channels = channels(), .cells = cells, .fast = fast, .work = work,
                  .no_bricks = no_bricks, .waves = waves, .texel_bytes = texel_bytes};
  v.gradient = s.gradient_opacity.enabled;
  v.depth_color = s.depth_color != DepthColorMode::kOff;
  v.gamma = any_gamma(s, v.channels);
  v.naive_opacity = !s.opacity_correction;
  v.composite = s.blend == ChannelBlend::kComposite;
  v.hue_tables = hue_lookups(model);
  return variant(v);
}

bool BrickRenderer::hue_lookups(uint32_t model) const {
  // Only E-A and emission look up every sample; a variant more for the
  // others' one lookup a ray would only cost its compile.
  if (!opt_.hue_tables || (model != VXR_MODEL_EMISSION_ABSORPTION && model != VXR_MODEL_EMISSION)) return false;
  // Every channel the shader may look up (the iso channel need not be drawn).
  for (uint32_t c = 0; c < channels(); ++c)
    if (!tf_hues_[c]) return false;
  return true;
}

Result<const gpu::ComputePipeline*> BrickRenderer::classify_pipeline(const RenderSettings& s, uint32_t model) {
  ShaderVariant v{.model = model, .channels = channels(), .cells = true, .classify = true};
  v.gamma = any_gamma(s, v.channels);
  return variant(v);
}

static_assert(uint32_t(SampleWork::kShade) == VXR_SAMPLE_SHADE && uint32_t(SampleWork::kFetchOnly) == VXR_SAMPLE_FETCH_ONLY &&
                  uint32_t(SampleWork::kMarchOnly) == VXR_SAMPLE_MARCH_ONLY,
              "SampleWork is spec constant 107's value");

Result<const gpu::ComputePipeline*> BrickRenderer::variant(const ShaderVariant& v) {
  // Looked up every view of every frame: a fixed-size key, the vector only for a build.
  const std::array<gpu::SpecializationConstant, kVariantConstants> constants = {{
      {100, v.model},
      {101, v.channels},
      {102, v.gradient},
      {103, v.depth_color},
      {104, v.gamma},
      {105, v.naive_opacity},
      {106, v.cells},
      {107, uint32_t(v.work)},
      {108, v.fast.record_texels},
      {109, v.fast.cell_bits},
      {110, v.no_bricks},
      {111, v.fast.key_texels},
      {112, v.composite ? uint32_t(VXR_BLEND_COMPOSITE) : uint32_t(VXR_BLEND_ADDITIVE)},
      {113, v.waves},
      {114, v.classify},
      {115, v.texel_bytes},
      {116, v.hue_tables}}};
  VariantKey key;  // the constants' values identify the variant
  for (size_t i = 0; i < constants.size(); ++i) key[i] = constants[i].value;
  std::map<VariantKey, gpu::ComputePipeline>& variants = pipes_->variants;
  if (auto it = variants.find(key); it != variants.end()) return &it->second;
  VXR_ASSIGN_OR_RETURN(gpu::ComputePipeline p,
                       gpu::create_compute_pipeline(ctx_, {"brick_raycast.comp", bindings(),
                                                           sizeof(shader::BrickCastParams),
                                                           {constants.begin(), constants.end()}}));
  return &variants.emplace(key, std::move(p)).first->second;
}

BrickRenderer::Atlases BrickRenderer::pool_atlases() const {
  Atlases out;
  for (uint32_t c = 0; c < pool_->channels(); ++c) {
    out.images.push_back(&pool_->atlas(c));
    if (pool_->atlas_texels_view(c)) out.texels.push_back(pool_->atlas_texels_view(c));
  }
  return out;
}

void BrickRenderer::bind_atlases(VkDescriptorSet set, const Atlases& atlases) {
  // Slots past the drawn channels repeat channel 0's (never read: the shader
  // is specialised for the channel count).
  VkWriteDescriptorSet w[2] = {};
  VkDescriptorImageInfo infos[VXR_MAX_CHANNELS];
  VkBufferView views[VXR_MAX_CHANNELS];
  const size_t n = atlases.images.size(), nt = atlases.texels.size();
  for (size_t c = 0; c < VXR_MAX_CHANNELS; ++c) {
    if (n) infos[c] = {linear_, atlases.images[c < n ? c : 0]->view, atlases.images[c < n ? c : 0]->layout};
    views[c] = nt ? atlases.texels[c < nt ? c : 0]->view.get() : no_texels_.get();
  }
  uint32_t writes = 0;
  if (n) {
    w[writes].dstBinding = 0;
    w[writes].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w[writes++].pImageInfo = infos;
  }
  w[writes].dstBinding = 17;
  w[writes].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
  w[writes++].pTexelBufferView = views;
  for (uint32_t i = 0; i < writes; ++i) {
    w[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    w[i].dstSet = set;
    w[i].descriptorCount = VXR_MAX_CHANNELS;
  }
  vkUpdateDescriptorSets(ctx_.device(), writes, w, 0, nullptr);
}

BrickRenderer::Atlases BrickRenderer::mono_atlases() const {
  Atlases out;
  for (const gpu::Image& t : mono_tex_) out.images.push_back(&t);
  for (const gpu::ImageTexels& t : mono_texels_) out.texels.push_back(&t);
  return out;
}

BrickRenderer::AtlasReads BrickRenderer::reads_of(const gpu::Image& a, bool by_hand) {
  AtlasReads r;
  r.texels = {a.extent.width, a.extent.height, a.extent.depth};
  if (by_hand) {
    // 1: u8 texels in quads, 2: u16 in pairs (write_texel_words: the image is wider).
    r.texel_bytes = gpu::format_texel_bytes(a.format);
    r.texels.x /= texel_word_width(a.format);
    const uint32_t element = gpu::format_texel_bytes(kAtlasTexelElement);  // pitches in view elements
    r.pitch = {uint32_t(a.row_pitch / element), uint32_t(a.depth_pitch / element)};
  }
  return r;
}

namespace {
// Gradient opacity and the isosurface normal read +-1 voxel around a sample.
bool needs_gradients(const RenderSettings& s) {
  return s.gradient_opacity.enabled || s.model == OpticalModel::kIsosurface;
}
}  // namespace

Status BrickRenderer::prepare(const RenderSettings& s) {
  if (!needs_gradients(s) || pool_->apron() >= 2) return Status::ok();
  return rebuild_pool(2);
}

Status BrickRenderer::rebuild_pool(uint32_t apron) {
  // Once per renderer: the bricks are loaded again with the wider apron. The
  // old atlases may still be read by a submitted frame, and every view's set
  // names them: wait for the device, then replace and rebind. Callers run
  // this before any of this frame's commands are recorded (prepare,
  // begin_frame), so no recording command buffer has bound a set yet.
  BrickPoolOptions po = opt_.pool;
  po.apron = apron;
  po.channels.clear();
  for (uint32_t c = 0; c < pool_->channels(); ++c) po.channels.push_back(pool_->source_channel(c));
  if (VkResult vr = vkDeviceWaitIdle(ctx_.device()); vr != VK_SUCCESS)
    return internal_error("brick renderer: vkDeviceWaitIdle failed (" + std::to_string(int(vr)) + ")");
  pool_.reset();
  occupied_.clear();
  VXR_ASSIGN_OR_RETURN(pool_, BrickPool::create(ctx_, src_, po));
  opt_.pool = po;
  for (VkDescriptorSet set : view_sets_) bind_atlases(set, pool_atlases());
  VXR_RETURN_IF_ERROR(ensure_cell_keys());
  for (VkDescriptorSet set : view_sets_) gpu::write_storage_buffer(ctx_, set, 8, pool_->cell_ranges().buffer);
  gpu::write_storage_buffer(ctx_, mono_set_, 8, pool_->cell_ranges().buffer);
  // Requested bricks are keyed the same; the new pool has none of them yet.
  return pin_resident(pinned_timepoint_);
}

Status BrickRenderer::ensure_timepoint(uint32_t timepoint) {
  if (timepoint >= src_.info().timepoints)
    return invalid_argument("render: timepoint " + std::to_string(timepoint) + " asked for, the volume has " +
                            std::to_string(src_.info().timepoints) + " (0.." +
                            std::to_string(src_.info().timepoints - 1) + ")");
  if (timepoint == pinned_timepoint_) return Status::ok();
  VXR_RETURN_IF_ERROR(pin_resident(timepoint));
  pinned_timepoint_ = timepoint;
  return Status::ok();
}

namespace {
bool is_empty(const BrickBox& b) { return !(b.lo.x < b.hi.x && b.lo.y < b.hi.y && b.lo.z < b.hi.z); }
}  // namespace

BrickBox BrickRenderer::march_box(const ChunkKey& key, const LodSettings& clip, const CellOpacity* cells,
                                  CellFacts* facts, const std::vector<BrickBox>** blocks) {
  const BrickBox box = chunk_box(src_, key);
  const auto& ds_u = src_.levels()[key.level].downsample;
  const glm::dvec3 ds(ds_u[0], ds_u[1], ds_u[2]);
  BrickBox m{glm::dvec3(0.0), (box.hi - box.lo) / ds};
  if (clip.roi.enabled) {
    m.lo = glm::max(m.lo, (clip.roi.lo - box.lo) / ds);
    m.hi = glm::min(m.hi, (clip.roi.hi - box.lo) / ds);
  }
  if (blocks) *blocks = nullptr;
  if (!cells) return m;
  // Samples outside the kept cells lie in cells whose ranges cover every
  // voxel they filter: zero opacity, nothing to add. The box of the kept
  // cells grows by half the cells' band: a sample within rounding of its face
  // is within the band of such a cell too.
  const uint32_t slot = pool_->slot_of(key);
  if (occupied_.size() != pool_->capacity()) occupied_.assign(pool_->capacity(), {});
  OccupiedCells& oc = occupied_[slot];
  // Cell k of an axis covers [k * s - 0.5, (k + 1) * s - 0.5) (shared/brick_params.h).
  const double s = pool_->cells().cell_size, grow = 0.5 * VXR_CELL_BAND;
  if (oc.settings != cells->hash() || !(oc.key == key)) {
    const uint32_t n = pool_->cells().cells_per_axis, count = pool_->cells().count();
    const auto* ranges = static_cast<const glm::vec2*>(pool_->cell_ranges().mapped);
    std::vector<uint8_t>& kept = kept_scratch_;  // reused: settings changes recompute every drawn brick
    kept.assign(count, 0);
    glm::uvec3 lo(n), hi(0);
    uint32_t kept_count = 0;
    CellFacts minip;  // lowest_max, minima
    const bool one_minip = cells->model() == OpticalModel::kMinIp && cells->channels() == 1;
    for (uint32_t z = 0; z < n; ++z)
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x) {
          const uint32_t cell = (z * n + y) * n + x;
          if (one_minip) {
            const glm::vec2 r = ranges[size_t(slot) * count + cell];
            minip.lowest_max = std::min(minip.lowest_max, float(cells->windowed(0, r.y)));
            ++minip.minima[std::min<uint32_t>(kMinIpBins - 1, uint32_t(cells->windowed(0, r.x) * kMinIpBins))];
          }
          for (uint32_t c = 0; c < cells->channels(); ++c)
            if (cells->may_contribute(c, ranges[(size_t(slot) * cells->channels() + c) * count + cell])) {
              kept[cell] = 1;
              ++kept_count;
              lo = glm::min(lo, glm::uvec3(x, y, z));
              hi = glm::max(hi, glm::uvec3(x, y, z) + 1u);
              break;
            }
        }
    // Groups of 2x2x2 cells with some cell kept: how many of their cells are empty.
    uint32_t split = 0;
    for (uint32_t z = 0; z < n; z += 2)
      for (uint32_t y = 0; y < n; y += 2)
        for (uint32_t x = 0; x < n; x += 2) {
          uint32_t in = 0, k = 0;
          for (uint32_t j = 0; j < 8; ++j) {
            const glm::uvec3 f(x + (j & 1), y + ((j >> 1) & 1), z + (j >> 2));
            if (f.x >= n || f.y >= n || f.z >= n) continue;
            ++in;
            k += kept[(f.z * n + f.y) * n + f.x];
          }
          if (k > 0) split += in - k;
        }
    // The groups a ray may cross: those meeting the box of kept cells.
    const glm::uvec3 glo = lo / 2u, ghi = (hi + 1u) / 2u;
    const bool any = glm::all(glm::lessThan(lo, hi));
    const uint32_t boxed = any ? (ghi.x - glo.x) * (ghi.y - glo.y) * (ghi.z - glo.z) : 0;
    const bool all_kept = any && kept_count == (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
    oc.key = key, oc.settings = cells->hash(), oc.lo = lo, oc.hi = hi;
    oc.facts = {split, boxed, all_kept, kept_count == count, kept_count == 0, minip.lowest_max, minip.minima};
    oc.blocks.clear();  // (keeps its capacity: settings changes recompute every drawn brick)
    // Blocks of kBlockCells^3 cells: the tight box of each one's kept cells, grown as the march box.
    const uint32_t bc = kBlockCells, nb = (n + bc - 1) / bc;
    for (uint32_t bz = 0; bz < nb; ++bz)
      for (uint32_t by = 0; by < nb; ++by)
        for (uint32_t bx = 0; bx < nb; ++bx) {
          glm::uvec3 blo(n), bhi(0);
          for (uint32_t z = bz * bc; z < std::min(n, bz * bc + bc); ++z)
            for (uint32_t y = by * bc; y < std::min(n, by * bc + bc); ++y)
              for (uint32_t x = bx * bc; x < std::min(n, bx * bc + bc); ++x)
                if (kept[(z * n + y) * n + x]) {
                  blo = glm::min(blo, glm::uvec3(x, y, z));
                  bhi = glm::max(bhi, glm::uvec3(x, y, z) + 1u);
                }
          if (glm::all(glm::lessThan(blo, bhi)))
            oc.blocks.push_back({glm::dvec3(blo) * s - 0.5 - grow, glm::dvec3(bhi) * s - 0.5 + grow});
        }
  }
  if (facts) *facts = oc.facts;
  if (blocks) *blocks = &oc.blocks;
  // An average whose rays show entry 0 is cast wherever the volume is:
  // whole bricks, walking past their empty cells.
  if (cells->marches_whole_bricks()) return m;
  m.lo = glm::max(m.lo, glm::dvec3(oc.lo) * s - 0.5 - grow);
  m.hi = glm::min(m.hi, glm::dvec3(oc.hi) * s - 0.5 + grow);
  return m;
}

void BrickRenderer::fill_record(void* out, const ChunkKey& key, const glm::vec3& atlas_origin, const LodView& view,
                                const LodSettings& clip, const BrickBox& local, bool walk, bool no_samples) const {
  // Everything in double, then local (small) numbers to float.
  const BrickBox box = chunk_box(src_, key);
  const auto& ds_u = src_.levels()[key.level].downsample;
  const glm::dvec3 ds(ds_u[0], ds_u[1], ds_u[2]);
  shader::BrickRecord r{};
  r.eye = v4((view.eye - box.lo) / ds);
  r.scale = v4(1.0 / ds);
  // An empty box as lo = hi: every ray misses it.
  r.box_lo = v4(local.lo);
  r.box_hi = v4(glm::max(local.lo, local.hi));
  r.box_lo.w = walk ? 0.0f : 1.0f;
  r.box_hi.w = no_samples ? 1.0f : 0.0f;
  r.atlas = glm::vec4(atlas_origin, float(pool_->slot_of(key)));  // w: the slot, for its cell ranges
  if (clip.cut.enabled) {
    // dot(n, lo0 + ds * p) + d  ->  dot(n * ds, p) + dot(n, lo0) + d, normalised.
    const glm::dvec3 n = clip.cut.normal * ds;
    const double len = glm::length(n);
    if (len > 0) r.plane = v4(n / len, (glm::dot(clip.cut.normal, box.lo) + clip.cut.offset) / len);
  }
  std::memcpy(out, &r, sizeof(r));
}

bool BrickRenderer::clears_tiled_view(const RenderTarget& target, uint32_t w, uint32_t h) const {
  if (target.under.present() || !opt_.clear_empty_tiles) return false;
  const bool direct = target.storage_view != VK_NULL_HANDLE && target.format == VK_FORMAT_R8G8B8A8_UNORM;
  const VkOffset2D at = target.rect.offset;
  return !direct || (at.x == 0 && at.y == 0 && w == target.extent.width && h == target.extent.height);
}

bool BrickRenderer::minip_walk_pays(const CellFacts& f) {
  // A MinIP ray can skip a cell only once its running minimum is at most the
  // cell's minimum, and each cell a ray walks costs it about four samples.
  // A ray that crossed the cell with the lowest maximum has a minimum at most
  // that: the cells whose minimum lies above it are the ones any ray could
  // skip. Where they are under half the cells, the rays march without a
  // walk. The sparse vessels over noise 0..6, window 0..200 (`vxr render
  // procedural:vessels:256 --model minip --window 0,200`): 256-258 GPU ms
  // walked against 185-215 with nothing skipped; the MRI, whose background
  // is exactly 0 and whose rays then skip every cell, 35.8 against 64.8 ms.
  const uint32_t first = std::min<uint32_t>(kMinIpBins, uint32_t(std::ceil(double(f.lowest_max) * kMinIpBins)));
  uint64_t above = 0, all = 0;
  for (uint32_t b = 0; b < kMinIpBins; ++b) {
    all += f.minima[b];
    if (b >= first) above += f.minima[b];
  }
  return 2 * above >= all;
}

bool BrickRenderer::iso_skips(const RenderSettings& s) const { return iso_back_sample(s) && pool_->apron() >= 2; }

void BrickRenderer::set_clip(shader::RaycastParams& params, const RenderSettings& s, const LodSettings& clip) const {
  params.control2.w = iso_skips(s) ? 1u : 0u;
  if (clip.cut.enabled && glm::length(clip.cut.normal) > 0.0) {
    const double len = glm::length(clip.cut.normal);
    params.cut = glm::vec4(glm::dvec4(clip.cut.normal / len, clip.cut.offset / len));
  }
  if (!clip.roi.enabled) return;  // pack_params' region: the whole volume
  params.region_lo = glm::vec4(glm::max(glm::dvec3(params.region_lo), clip.roi.lo), 0.0f);
  params.region_hi = glm::vec4(glm::min(glm::dvec3(params.region_hi), clip.roi.hi), 0.0f);
}

Status BrickRenderer::record_cast(VkCommandBuffer cmd, VkDescriptorSet set, const RenderSettings& s, uint32_t model,
                                  uint32_t w, uint32_t h, uint32_t bricks, uint64_t records, const AtlasReads& atlas,
                                  BrickPassMode mode, const WorkSpans& spans, const RenderTarget& target,
                                  CellWalk cell_walk, SampleWork work, CellClassInputs* classify,
                                  BrickFrameStats* stats) {
  // RGBA8 UNORM with a storage view: the rays write it. Anything else (BGRA,
  // sRGB, float, no storage usage): final float pixels go to the
  // accumulation image and one blit converts them into the target's format.
  const bool direct = target.storage_view != VK_NULL_HANDLE && target.format == VK_FORMAT_R8G8B8A8_UNORM;
  if (!direct) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(ctx_.physical_device(), target.format, &fp);
    if (!(fp.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT))
      return unsupported("render target: format " + std::to_string(target.format) +
                         " is neither RGBA8 UNORM with a storage view nor a blit destination on this device");
  }
  const VkImageLayout final_layout =
      target.layout == VK_IMAGE_LAYOUT_UNDEFINED ? VK_IMAGE_LAYOUT_GENERAL : target.layout;
  const VkOffset2D at = target.rect.offset;
  // Every pass of a view with an underlay ends its rays at its depth.
  const uint32_t under = target.under.present() ? VXR_BRICK_UNDERLAY : 0u;
  const uint32_t out_flags = under | VXR_BRICK_STORE_FINAL | (target.opaque ? VXR_BRICK_OPAQUE : 0u) |
                             (is_unorm8(target.format) ? VXR_BRICK_QUANTIZE : 0u) |
                             (direct ? 0u : VXR_BRICK_FINAL_FLOAT);
  shader::BrickCastParams p{};
  // Empty-space cells: for the models whose empty samples change nothing
  // (average: its length is the ray's chord; iso where its crossings read
  // their sample back again, iso_skips).
  // MIP / MinIP test a cell against the ray's running value, so each cell
  // costs a walk; they pay from 8 samples a cell (4-voxel cells: step 0.5).
  // MRI MIP (`vxr render assets/mri-stack/volume.json --model mip --window
  // 75,200`, lavapipe, medians of alternating runs) with cells / without:
  // step 2 33.5 / 23.7 ms, step 1 40.2 / 37.9, step 0.5 48.8 / 62.7. An H200
  // (`vxr bench peer --size 2048`, skipping on / off) agrees: 3.7 / 2.2 GPU ms
  // at step 2, 3.9 / 3.7 at 1, 4.4 / 6.9 at 0.5.
  const bool reduce = model == VXR_MODEL_MIP || model == VXR_MODEL_MINIP;
  const BrickCells walk = walk_cells(pool_->cells(), reduce || cell_walk == CellWalk::kGroups);
  const bool cells = cell_walk != CellWalk::kOff &&
                     (model == VXR_MODEL_EMISSION_ABSORPTION || model == VXR_MODEL_EMISSION || model == VXR_MODEL_AVERAGE ||
                      (model == VXR_MODEL_ISOSURFACE && iso_skips(s)) || (reduce && walk.cell_size >= 8.0 * s.step_voxels));
  const uint32_t cells_per_axis = cells ? walk.cells_per_axis : 0u;
  if (!cells && stats) stats->bricks_walked = 0;  // record_view counted the bricks that would walk
  if (stats) stats->hue_lookups = hue_lookups(model);
  const uint32_t range_cells_per_axis = pool_->cells().cells_per_axis;
  // The records as texels of the whole table where the device's texel
  // buffers hold it (binding 15, the view's first at p.records.x); the E-A
  // and emission cell tests' bits through their uniform window when all of
  // the view's fit (binding 14 starts at the view's first); MIP / MinIP keys
  // as texels where the device has enough.
  FastReads fast;
  fast.record_texels = opt_.texel_brick_records && table_texels_fit_ && item_texels_fit_;
  fast.cell_bits = cells_per_axis > 0 && !reduce && opt_.uniform_cell_bits && classify &&
                   bricks * cell_bits_bytes(walk) <= cell_bits_window_bytes(classify->bits_offset);
  fast.key_texels = cells_per_axis > 0 && reduce && opt_.texel_cell_keys &&
                    cell_keys_.size / sizeof(float) <= ctx_.limits().maxTexelBufferElements;
  const gpu::ComputePipeline* pipe = nullptr;
  const bool waves = mode == BrickPassMode::kMultipass;
  VXR_ASSIGN_OR_RETURN(pipe, pipeline_for(s, model, atlas.texel_bytes, cells, fast, work, waves));
  const glm::uvec3& atlas_texels = atlas.texels;
  p.atlas_inv = glm::vec4(1.0f / atlas_texels.x, 1.0f / atlas_texels.y, 1.0f / atlas_texels.z,
                          float(walk.cell_size));
  p.texels = glm::uvec4(atlas.pitch, (atlas_texels.x - 1) | (atlas_texels.y - 1) << 16, atlas_texels.z - 1);
  p.records = glm::uvec4(uint32_t(records / sizeof(glm::vec4)), spans.list_texel, 0, 0);
  if (target.warp_x.active() || target.warp_y.active())
    p.warp = glm::uvec4(target.warp_x.active() ? target.warp_x.edge_warped : 0u,
                        target.warp_y.active() ? target.warp_y.edge_warped : 0u,
                        std::max(target.warp_x.step, target.warp_y.step), 0u);
  uint32_t dispatches = 0;

  // The previous view's dispatches and blit used the same accumulation image.
  full_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
               VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                   VK_ACCESS_2_SHADER_SAMPLED_READ_BIT | VK_ACCESS_2_UNIFORM_READ_BIT);
  if (direct)
    gpu::image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, target.layout, VK_IMAGE_LAYOUT_GENERAL,
                       VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  // A tiled frame's tiles that no brick touches, cleared where the image is
  // the view's alone (clear_empty_tiles): on lavapipe the dispatch of the
  // variant without bricks costs every ray a call of the shader (MRI E-A at
  // step 1, the render camera: 1.2-2 ms of a 40 ms frame).
  // With the marched tiles as their reached blocks (spans.by_groups) the
  // blocks left out are cleared too.
  VkImage cleared = VK_NULL_HANDLE;
  if (mode == BrickPassMode::kTiled && (spans.empty_tiles.y > 0 || spans.by_groups) && clears_tiled_view(target, w, h))
    cleared = direct ? target.image : accum_.image;
  if (cleared) {
    VkClearColorValue empty{};  // finish_ray of a ray that took no sample
    empty.float32[3] = target.opaque ? 1.0f : 0.0f;
    clear_image(cmd, cleared, empty);
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->pipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->layout, 0, 1, &set, 0, nullptr);
  bool classified = false;
  if (cells_per_axis > 0 && bricks > 0 && classify) {
    classify->model = model;
    classify->walked_cells = cells_per_axis;
    classify->range_cells = range_cells_per_axis;
    std::optional<CellClassInputs>& mine = classified_[views_];
    classified = mine && *mine == *classify;
    if (!classified) {
      forget_overwritten(views_, *classify);
      if (!mine) mine.emplace();
      std::swap(*mine, *classify);  // the caller's scratch keeps the old entry's storage
    }
  }
  if (cells_per_axis > 0 && bricks > 0 && !classified) {
    // The cells of the view's bricks classified once, so a ray's cell test is a load and a compare.
    const uint64_t per_brick = reduce ? walk.count() : cell_bits_bytes(walk) / 4;  // keys / words
    const gpu::ComputePipeline* classify_pipe = nullptr;
    VXR_ASSIGN_OR_RETURN(classify_pipe, classify_pipeline(s, model));
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, classify_pipe->pipeline);
    p.control = glm::uvec4(0, 0, 0, bricks);
    p.pass = glm::uvec4(0, cells_per_axis, VXR_BRICK_CLASSIFY, range_cells_per_axis);
    vkCmdPushConstants(cmd, classify_pipe->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(p), &p);
    vkCmdDispatch(cmd, bricks, uint32_t((per_brick + 63) / 64), 1);
    ++dispatches;
    if (stats) ++stats->classify_passes;
    compute_barrier(cmd);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->pipeline);
  }
  auto dispatch = [&](uint32_t first, uint32_t count, uint32_t flags) {
    p.control = glm::uvec4(uint32_t(at.x), uint32_t(at.y), first, count);
    p.pass = glm::uvec4(0, cells_per_axis, flags, range_cells_per_axis);
    vkCmdPushConstants(cmd, pipe->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(p), &p);
    vkCmdDispatch(cmd, (w + 7) / 8, (h + 7) / 8, 1);
    ++dispatches;
  };
  const uint32_t max_groups = ctx_.limits().maxComputeWorkGroupCount[0];
  // Workgroup i takes work entries span.x + i * per_workgroup on (in
  // dispatches of at most max_groups workgroups).
  auto dispatch_entries = [&](glm::uvec2 span, uint32_t flags, uint32_t per_workgroup = 1) {
    const uint32_t workgroups = span.y / per_workgroup;
    for (uint32_t done = 0; done < workgroups; done += max_groups) {
      p.control = glm::uvec4(uint32_t(at.x), uint32_t(at.y), 0, 0);
      p.pass = glm::uvec4(span.x + done * per_workgroup, cells_per_axis, flags, range_cells_per_axis);
      vkCmdPushConstants(cmd, pipe->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(p), &p);
      vkCmdDispatch(cmd, std::min(max_groups, workgroups - done), 1, 1);
      ++dispatches;
    }
  };
  if (mode == BrickPassMode::kSinglePass) {
    dispatch(0, bricks, out_flags);
  } else if (mode == BrickPassMode::kTiled) {
    // The tiles a brick touches march their lists; the others only write
    // what an empty ray gives, with the variant that has no brick loop.
    // Built with the marching variant, even while no tile is empty, so a
    // view that later leaves tiles empty builds no pipeline mid-session.
    VXR_ASSIGN_OR_RETURN(const gpu::ComputePipeline* empty_pipe,
                         pipeline_for(s, model, atlas.texel_bytes, false, {}, work, false, true));
    // The tiles whose bricks all march without a walk, with the variant
    // that has no cell code: lavapipe runs an if's code even where no lane
    // takes it, so a walk no ray needs still cost each brick a pass (`vxr
    // bench roofline`, dense 256^3 E-A: 0.571 -> 0.582 of the ceiling).
    const gpu::ComputePipeline* plain_pipe = pipe;
    if (cells_per_axis > 0) {
      FastReads no_cells = fast;
      no_cells.cell_bits = no_cells.key_texels = false;
      VXR_ASSIGN_OR_RETURN(plain_pipe, pipeline_for(s, model, atlas.texel_bytes, false, no_cells, work, false));
    }
    const uint32_t list_flags = VXR_BRICK_TILE_LISTS | VXR_BRICK_TILE_SUBSET | out_flags;
    if (plain_pipe == pipe) {
      // One dispatch: the plain tiles follow the marched ones in the list.
      dispatch_entries({spans.marched_tiles.x, spans.marched_tiles.y + spans.plain_tiles.y}, list_flags);
    } else {
      if (cleared && spans.by_groups) {
        dispatch_entries(spans.marched_groups, VXR_BRICK_TILE_LISTS | VXR_BRICK_BLOCK_SUBSET | out_flags, 8);
        if (stats) stats->groups_marched = spans.groups_reached;
      } else {
        dispatch_entries(spans.marched_tiles, list_flags);
      }
      if (spans.plain_tiles.y > 0) {
        if (spans.marched_tiles.y > 0) compute_barrier(cmd);  // other pixels of the same image (see below)
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, plain_pipe->pipeline);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, plain_pipe->layout, 0, 1, &set, 0, nullptr);
        dispatch_entries(spans.plain_tiles, list_flags);
      }
    }
    if (spans.empty_tiles.y > 0 && !cleared) {
      // Other pixels of the same image, but the validation layer tracks the
      // whole image (and the cell bits the shader can write).
      compute_barrier(cmd);
      pipe = empty_pipe;
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->pipeline);
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe->layout, 0, 1, &set, 0, nullptr);
      dispatch_entries(spans.empty_tiles, VXR_BRICK_TILE_SUBSET | out_flags);
    }
  } else {
    dispatch(0, 0, under | VXR_BRICK_STORE_ACCUM);  // clear
    for (const glm::uvec2& wave : spans.waves) {
      compute_barrier(cmd);  // a wave continues rays the previous one wrote
      dispatch_entries(wave, under | VXR_BRICK_WORK_ITEMS | VXR_BRICK_LOAD_ACCUM | VXR_BRICK_STORE_ACCUM);
    }
    compute_barrier(cmd);
    dispatch(0, 0, VXR_BRICK_LOAD_ACCUM | out_flags);
  }
  if (direct) {
    gpu::image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL, final_layout,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                       VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  } else {
    // The final pixels, written by the last dispatch, are the blit's source.
    gpu::image_barrier(cmd, accum_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
                       VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_BLIT_BIT,
                       VK_ACCESS_2_TRANSFER_READ_BIT);
    gpu::image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, target.layout,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                       VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_BLIT_BIT,
                       VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkImageBlit blit{};
    blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    blit.srcOffsets[1] = {int32_t(w), int32_t(h), 1};
    blit.dstOffsets[0] = {at.x, at.y, 0};
    blit.dstOffsets[1] = {at.x + int32_t(w), at.y + int32_t(h), 1};
    vkCmdBlitImage(cmd, accum_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target.image,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_NEAREST);
    gpu::image_barrier(cmd, accum_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                       VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    gpu::image_barrier(cmd, target.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, final_layout,
                       VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                       VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  }
  if (stats) stats->dispatches += dispatches;
  return Status::ok();
}

namespace {

// 0..n-1 in bit-reversed order (0, n/2, n/4, 3n/4, ... for n a power of
// two): every contiguous share of the sequence samples the whole range.
std::vector<uint32_t> interleaved_rows(uint32_t n) {
  uint32_t bits = 0;
  while ((1u << bits) < n) ++bits;
  std::vector<uint32_t> out;
  out.reserve(n);
  for (uint32_t i = 0; i < (1u << bits); ++i) {
    uint32_t r = 0;
    for (uint32_t b = 0; b < bits; ++b) r |= ((i >> b) & 1u) << (bits - 1 - b);
    if (r < n) out.push_back(r);
  }
  return out;
}

// Where world boxes fall in a view: the screen rectangle (pixels) a box
// covers, the whole image when it reaches behind the eye, and the view
// depths it spans (ray lengths in units of forward; from 0 when it reaches
// behind the eye). Built once per view: the tile lists project every kept
// block of every walked brick.
class ScreenBoxes {
 public:
  explicit ScreenBoxes(const LodView& v) : v_(v), inv_(glm::inverse(glm::dmat3(v.forward, v.right, v.up))) {}

  glm::uvec4 rect(const BrickBox& b, glm::dvec2* depth = nullptr) const {
    // p - eye = k.x f + k.y r + k.z u, affine in p: the corners from one and the edges.
    const glm::dvec3 k0 = inv_ * (b.lo - v_.eye), size = b.hi - b.lo;
    const glm::dvec3 ex = inv_[0] * size.x, ey = inv_[1] * size.y, ez = inv_[2] * size.z;
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300, d0 = 1e300, d1 = -1e300;
    bool behind = false;
    for (int c = 0; c < 8; ++c) {
      const glm::dvec3 k = k0 + ((c & 1) ? ex : glm::dvec3(0.0)) + ((c & 2) ? ey : glm::dvec3(0.0)) +
                           ((c & 4) ? ez : glm::dvec3(0.0));
      d0 = std::min(d0, k.x), d1 = std::max(d1, k.x);
      if (k.x <= 1e-9) {
        behind = true;
        continue;
      }
      const double nx = k.y / k.x, ny = -k.z / k.x;
      x0 = std::min(x0, nx), x1 = std::max(x1, nx), y0 = std::min(y0, ny), y1 = std::max(y1, ny);
    }
    if (depth) *depth = glm::dvec2(std::max(d0, 0.0), d1);
    if (behind) return {0, 0, v_.width, v_.height};
    auto px = [](double ndc, uint32_t n) { return (ndc + 1.0) * 0.5 * n - 0.5; };
    const double ax = std::clamp(std::floor(px(x0, v_.width)) - 1, 0.0, double(v_.width));
    const double bx = std::clamp(std::ceil(px(x1, v_.width)) + 2, 0.0, double(v_.width));
    const double ay = std::clamp(std::floor(px(y0, v_.height)) - 1, 0.0, double(v_.height));
    const double by = std::clamp(std::ceil(px(y1, v_.height)) + 2, 0.0, double(v_.height));
    return {uint32_t(ax), uint32_t(ay), uint32_t(bx - ax), uint32_t(by - ay)};
  }

 private:
  const LodView& v_;
  glm::dmat3 inv_;
};

// The rays of each 8x8 tile of a view as one centre ray and the NDC
// half-extents of the tile's pixel centres. A point that some ray of the
// tile reaches at view depth d lies within d (hx |right_i| + hy |up_i|) of
// the centre ray's point at that depth on every world axis i, so the depths
// where the tile's rays can meet a box are those where the centre ray meets
// the box grown by that much (taken at the box's farthest depth): a chord,
// much tighter than the depths of the box's corners when the box is oblique.
// The same for a tile's 4x2 blocks (a SIMD group's rays on lavapipe), whose
// rays are made for a tile when first asked for.
class TileFrusta {
 public:
  // Per tile or block, two vectors (`s`, kept by the caller between views):
  // the centre ray's inverse per unit view depth, and how far the others
  // stray from it per world axis per unit view depth. A block's are made
  // when first asked for; `groups` false: never asked (no storage for them).
  TileFrusta(const LodView& v, const WarpAxis& ax, const WarpAxis& ay, TileRayScratch& s, bool groups)
      : view_(v), columns_((ax.warped() + 7) / 8), s_(s) {
    const size_t rows = (ay.warped() + 7) / 8;
    s_.tiles.resize(2 * columns_ * rows);
    for (size_t ty = 0; ty < rows; ++ty) {
      const glm::dvec2 y = ndc_span(ay, ty * 8, 8);
      for (size_t tx = 0; tx < columns_; ++tx) pixel_rays(ndc_span(ax, tx * 8, 8), y, &s_.tiles[2 * (ty * columns_ + tx)]);
    }
    if (!groups) return;
    group_columns_ = (ax.warped() + 3) / 4;
    group_rows_ = (ay.warped() + 1) / 2;
    s_.group_spans.resize(group_columns_ + group_rows_);
    for (size_t i = 0; i < group_columns_; ++i) s_.group_spans[i] = ndc_span(ax, i * 4, 4);
    for (size_t i = 0; i < group_rows_; ++i) s_.group_spans[group_columns_ + i] = ndc_span(ay, i * 2, 2);
    s_.groups.resize(16 * columns_ * rows);
    s_.groups_made.assign(columns_ * rows, 0);
  }

  // A box whose corners span view depths `span`, made ready for depths():
  // grown past float rounding of the rays, relative to the eye.
  struct Box {
    glm::dvec3 lo, hi;
    glm::dvec2 span;
  };
  Box prepare(const BrickBox& box, glm::dvec2 span) const {
    const glm::dvec3 margin = 1e-4 * (box.hi - box.lo) + 1e-6 * (glm::abs(view_.eye) + 1.0);
    return {box.lo - margin - view_.eye, box.hi + margin - view_.eye, glm::dvec2(std::max(span.x, 0.0), span.y)};
  }

  // The view depths where tile (tx, ty)'s rays can meet the box, within
  // its corners' depths; empty (x > y) where none does.
  glm::dvec2 depths(uint32_t tx, uint32_t ty, const Box& box) const {
    return chord(&s_.tiles[2 * (size_t(ty) * columns_ + tx)], box);
  }

  // Whether the rays of 4x2 block `group` of tile (tx, ty) (column group & 1,
  // row group >> 1, as the shader's subgroups take them) can meet the box.
  bool group_meets(uint32_t tx, uint32_t ty, uint32_t group, const Box& box) {
    const size_t column = tx * 2 + (group & 1), row = ty * 4 + (group >> 1);
    if (column >= group_columns_ || row >= group_rows_) return false;  // past the image: no rays
    const size_t tile = size_t(ty) * columns_ + tx;
    glm::dvec3* t = &s_.groups[16 * tile + 2 * group];
    if (!(s_.groups_made[tile] & (1u << group))) {
      pixel_rays(s_.group_spans[column], s_.group_spans[group_columns_ + row], t);
      s_.groups_made[tile] |= uint8_t(1u << group);
    }
    const glm::dvec2 c = chord(t, box);
    return c.x <= c.y;
  }

 private:
  static glm::dvec2 chord(const glm::dvec3* t, const Box& box) {
    const glm::dvec3 grow = std::max(box.span.y, 0.0) * t[1];  // for the tile's other rays, at the farthest depth
    const glm::dvec3 a = (box.lo - grow) * t[0], b = (box.hi + grow) * t[0];
    const glm::dvec3 near = glm::min(a, b), far = glm::max(a, b);
    return {std::max({box.span.x, near.x, near.y, near.z}), std::min({box.span.y, far.x, far.y, far.z})};
  }
  // The centre ray and stray of the pixels whose NDC spans are x and y (ndc_span).
  void pixel_rays(glm::dvec2 x, glm::dvec2 y, glm::dvec3* out) const {
    // The centre ray per unit view depth (the shader's raw_dir); an axis
    // it does not move along gets a huge inverse, never 0 * inf.
    glm::dvec3 dir = view_.forward + x.x * view_.right - y.x * view_.up;
    dir = glm::mix(dir, glm::dvec3(1e-300), glm::equal(dir, glm::dvec3(0.0)));
    out[0] = 1.0 / dir;
    out[1] = x.y * glm::abs(view_.right) + y.y * glm::abs(view_.up);
  }
  // Pixels [first, first + count) along an axis: the centre and half-extent in NDC of their centres.
  static glm::dvec2 ndc_span(const WarpAxis& a, size_t first, size_t count) {
    const uint32_t n = a.warped();
    auto ndc = [&](size_t px) { return a.from_warped(px + 0.5) / a.full * 2.0 - 1.0; };  // monotonic in px
    const double lo = ndc(first), hi = ndc(std::min<size_t>(first + count - 1, n - 1));
    return {0.5 * (lo + hi), 0.5 * (hi - lo) + 1e-5};
  }
  const LodView& view_;
  size_t columns_, group_columns_ = 0, group_rows_ = 0;
  TileRayScratch& s_;
};

// The 4x2 blocks of 8x8 tile (tx, ty) that pixel rectangle r (x, y, width,
// height) overlaps: bit 2 * row + column, as the shader's subgroups take them
// (VXR_BRICK_BLOCK_SUBSET).
uint8_t groups_in(const glm::uvec4& r, uint32_t tx, uint32_t ty) {
  const int x0 = std::max(int(r.x) - int(tx * 8), 0), x1 = std::min(int(r.x + r.z) - int(tx * 8), 8) - 1;
  const int y0 = std::max(int(r.y) - int(ty * 8), 0), y1 = std::min(int(r.y + r.w) - int(ty * 8), 8) - 1;
  if (x0 > x1 || y0 > y1) return 0;
  const uint32_t columns = (2u << (x1 / 4)) - (1u << (x0 / 4));  // bit per column x0 / 4 .. x1 / 4
  uint32_t m = 0;
  for (int row = y0 / 2; row <= y1 / 2; ++row) m |= columns << (2 * row);
  return uint8_t(m);
}

// A block entry's pixel for padding: past any image, so its rays return at once.
constexpr uint32_t kPastImage = 0x40000000u;

// The warped-grid pixels covering full-image rectangle r (identity without a warp).
glm::uvec4 warp_rect(const glm::uvec4& r, const WarpAxis& ax, const WarpAxis& ay) {
  const uint32_t x0 = uint32_t(std::floor(ax.to_warped(r.x))), y0 = uint32_t(std::floor(ay.to_warped(r.y)));
  const uint32_t x1 = std::min(ax.warped(), uint32_t(std::ceil(ax.to_warped(double(r.x) + r.z))));
  const uint32_t y1 = std::min(ay.warped(), uint32_t(std::ceil(ay.to_warped(double(r.y) + r.w))));
  return {x0, y0, x1 > x0 ? x1 - x0 : 0u, y1 > y0 ? y1 - y0 : 0u};
}
}  // namespace

Result<std::vector<glm::uvec2>> BrickRenderer::build_waves(const std::vector<BrickBox>& boxes, const LodView& view,
                                                           const WarpAxis& ax, const WarpAxis& ay, glm::uvec4* dst, size_t capacity, size_t* used) {
  // Each brick becomes one work item per 8x8 tile holding a pixel whose ray
  // hits its march box. A brick goes into the wave after the last wave that wrote any of
  // its pixels, so within a wave no two items write the same pixel (the shader
  // leaves pixels that miss its brick alone) and every pixel still sees its
  // bricks front to back across waves. Conflicts are tested per pixel (a ray
  // against the march box grown by 0.1%, conservative against float error):
  // per tile, bricks that merely touch on screen would chain into as many
  // waves as bricks.
  const uint32_t w = ax.warped(), h = ay.warped();
  const uint32_t tw = (w + 7) / 8, th = (h + 7) / 8;
  const glm::uvec4 grid(ax.full, ay.full, ax.edge_full, ay.edge_full);
  if (ray_dirs_.size() != size_t(w) * h || rays_for_ != std::make_tuple(view.forward, view.right, view.up) ||
      rays_grid_ != grid) {
    ray_dirs_.resize(size_t(w) * h);
    rays_grid_ = grid;
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const double nx = ax.from_warped(x + 0.5) / ax.full * 2.0 - 1.0;
        const double ny = ay.from_warped(y + 0.5) / ay.full * 2.0 - 1.0;
        const glm::dvec3 d = glm::normalize(view.forward + nx * view.right - ny * view.up);
        ray_dirs_[size_t(y) * w + x] = 1.0 / d;  // inverse: the slab test divides
      }
    rays_for_ = std::make_tuple(view.forward, view.right, view.up);
  }
  pixel_wave_.assign(size_t(w) * h, 0);
  const ScreenBoxes screen(view);
  std::vector<uint8_t> tile_hit(size_t(tw) * th, 0);
  struct Item {
    uint32_t wave, brick, tx, ty;
  };
  std::vector<Item> items;
  uint32_t waves = 0;
  std::vector<uint32_t> hit_pixels;
  for (uint32_t b = 0; b < boxes.size(); ++b) {
    if (is_empty(boxes[b])) continue;
    const glm::uvec4 r = warp_rect(screen.rect(boxes[b]), ax, ay);
    if (r.z == 0 || r.w == 0) continue;
    BrickBox box = boxes[b];
    const glm::dvec3 grow = 1e-3 * (box.hi - box.lo);
    box.lo -= grow;
    box.hi += grow;
    const glm::dvec3 lo = box.lo - view.eye, hi = box.hi - view.eye;
    hit_pixels.clear();
    uint32_t wave = 0;
    for (uint32_t y = r.y; y < r.y + r.w; ++y)
      for (uint32_t x = r.x; x < r.x + r.z; ++x) {
        const glm::dvec3& inv = ray_dirs_[size_t(y) * w + x];
        const glm::dvec3 ta = lo * inv, tb = hi * inv;
        const glm::dvec3 tmin = glm::min(ta, tb), tmax = glm::max(ta, tb);
        const double t0 = std::max({tmin.x, tmin.y, tmin.z, 0.0}), t1 = std::min({tmax.x, tmax.y, tmax.z});
        if (!(t1 >= t0)) continue;
        const uint32_t pi = y * w + x;
        hit_pixels.push_back(pi);
        wave = std::max(wave, pixel_wave_[pi]);
      }
    if (hit_pixels.empty()) continue;
    for (uint32_t pi : hit_pixels) {
      pixel_wave_[pi] = wave + 1;
      const size_t t = size_t((pi / w) / 8) * tw + (pi % w) / 8;
      if (tile_hit[t] != 1) {
        tile_hit[t] = 1;
        items.push_back({wave, b, uint32_t((pi % w) / 8) * 8, uint32_t((pi / w) / 8) * 8});
      }
    }
    for (uint32_t pi : hit_pixels) tile_hit[size_t((pi / w) / 8) * tw + (pi % w) / 8] = 0;
    waves = std::max(waves, wave + 1);
  }
  if (items.size() > capacity) {
    *used = items.size();  // record_view grows the list to this and builds again
    return out_of_range("render: the view needs " + std::to_string(items.size()) + " brick tiles, the frame's work "
                        "list has room for " + std::to_string(capacity) + "; raise the LOD bias or use a smaller image");
  }
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.wave < b.wave; });
  std::vector<glm::uvec2> out(waves, glm::uvec2(0));
  *used = items.size();
  for (uint32_t i = 0; i < items.size(); ++i) {
    dst[i] = glm::uvec4(items[i].brick, items[i].tx, items[i].ty, 0);
    if (out[items[i].wave].y == 0) out[items[i].wave].x = i;
    ++out[items[i].wave].y;
  }
  return out;
}

Status BrickRenderer::build_tile_lists(const std::vector<BrickBox>& boxes, const std::vector<uint8_t>& walks,
                                       const std::vector<glm::uvec2>& blocks, const std::vector<BrickBox>& block_boxes,
                                       const LodView& view, const WarpAxis& ax, const WarpAxis& ay, bool by_groups,
                                       bool keep_rays, glm::uvec4* dst, size_t capacity, size_t* used,
                                       WorkSpans* spans) {
  const uint32_t tw = (ax.warped() + 7) / 8, th = (ay.warped() + 7) / 8;
  spans->blocks = 0;
  spans->by_groups = by_groups;
  // Scratch kept between views: no allocation per view once sizes settle.
  std::vector<std::vector<TileEntry>>& lists = tile_entries_;
  lists.resize(size_t(tw) * th);
  for (auto& l : lists) l.clear();
  std::vector<glm::dvec2>& depths = tile_depths_;
  // Per tile, its 4x2 blocks (bit 2 * row + column) whose rays some entry can reach.
  std::vector<uint8_t>& reached = tile_groups_;
  reached.assign(by_groups ? lists.size() : 0, 0);
  tile_rays_.group_tests.clear();
  const ScreenBoxes screen(view);
  std::optional<TileFrusta> frusta;  // built for the view's first brick with blocks
  size_t total = lists.size();
  const glm::vec2 all_depths(0.0f, std::numeric_limits<float>::infinity());
  for (uint32_t b = 0; b < boxes.size(); ++b) {
    if (is_empty(boxes[b])) continue;
    const glm::uvec4 r = warp_rect(screen.rect(boxes[b]), ax, ay);
    if (r.z == 0 || r.w == 0) continue;
    const glm::uvec2 t0 = glm::uvec2(r.x, r.y) / 8u, t1 = (glm::uvec2(r.x + r.z, r.y + r.w) - 1u) / 8u;
    // A brick within one tile gains little from its blocks (its rays clip
    // to its box), and past the view's budget they cost more CPU than they save.
    const uint32_t n_blocks = blocks[b].y - blocks[b].x;
    if (n_blocks == 0 || t0 == t1 || spans->blocks + n_blocks > opt_.max_tile_blocks) {
      for (uint32_t y = t0.y; y <= t1.y; ++y)
        for (uint32_t x = t0.x; x <= t1.x; ++x) {
          lists[size_t(y) * tw + x].push_back({b, all_depths});
          if (by_groups) reached[size_t(y) * tw + x] |= groups_in(r, x, y);
        }
      continue;
    }
    spans->blocks += n_blocks;
    // Per tile of the brick's rectangle, the depths its blocks span there.
    const uint32_t rw = t1.x - t0.x + 1;
    depths.assign(size_t(rw) * (t1.y - t0.y + 1), glm::dvec2(1e300, -1e300));
    for (uint32_t i = blocks[b].x; i < blocks[b].y; ++i) {
      glm::dvec2 d;
      const glm::uvec4 q = warp_rect(screen.rect(block_boxes[i], &d), ax, ay);
      if (q.z == 0 || q.w == 0) continue;
      const glm::uvec2 q0 = glm::max(glm::uvec2(q.x, q.y) / 8u, t0);
      const glm::uvec2 q1 = glm::min((glm::uvec2(q.x + q.z, q.y + q.w) - 1u) / 8u, t1);
      if (!frusta) frusta.emplace(view, ax, ay, tile_rays_, by_groups);
      const TileFrusta::Box block = frusta->prepare(block_boxes[i], d);
      for (uint32_t y = q0.y; y <= q1.y; ++y)
        for (uint32_t x = q0.x; x <= q1.x; ++x) {
          const glm::dvec2 c = frusta->depths(x, y, block);
          if (!(c.x <= c.y)) continue;  // the tile's rays pass the block by
          glm::dvec2& e = depths[size_t(y - t0.y) * rw + (x - t0.x)];
          e = glm::dvec2(std::min(e.x, c.x), std::max(e.y, c.y));
          if (!by_groups) continue;
          uint8_t& r = reached[size_t(y) * tw + x];
          if (r == 0xff) continue;
          // A rectangle over the whole tile (inside a dense volume's
          // silhouette) reaches all its blocks unasked. Elsewhere each block
          // under the rectangle is tested by its own chord, once every brick
          // is in (a later rectangle may cover the tile): a test costs about
          // 30 ns, a block left in only its rays' time.
          if (q.x <= x * 8 && q.y <= y * 8 && q.x + q.z >= x * 8 + 8 && q.y + q.w >= y * 8 + 8) r = 0xff;
          else tile_rays_.group_tests.push_back({size_t(y) * tw + x, block.lo, block.hi, block.span, groups_in(q, x, y)});
        }
    }
    for (uint32_t y = t0.y; y <= t1.y; ++y)
      for (uint32_t x = t0.x; x <= t1.x; ++x) {
        const glm::dvec2 e = depths[size_t(y - t0.y) * rw + (x - t0.x)];
        if (!(e.x <= e.y)) {  // no block here: its rays would find every cell empty
          // An average that shows entry 0 casts these rays too: an entry whose depths clip every sample.
          if (keep_rays) lists[size_t(y) * tw + x].push_back({b, glm::vec2(0.0f, 0.0f)});
          continue;
        }
        // Widened well past float rounding of the rays' depths.
        const double margin = 1e-4 * e.y + 1e-3;
        lists[size_t(y) * tw + x].push_back({b, glm::vec2(float(std::max(0.0, e.x - margin)), float(e.y + margin))});
      }
  }
  // The tiles' blocks no rectangle covered, each by its chord.
  for (const TileRayScratch::GroupTest& g : tile_rays_.group_tests) {
    uint8_t& r = reached[g.tile];
    for (uint8_t open = g.groups & ~r; open != 0; open &= uint8_t(open - 1)) {
      const uint32_t bit = uint32_t(std::countr_zero(open));
      if (frusta->group_meets(uint32_t(g.tile % tw), uint32_t(g.tile / tw), bit, {g.lo, g.hi, g.span})) r |= uint8_t(1u << bit);
    }
  }
  for (const auto& l : lists) total += l.size();
  spans->tile_entries = static_cast<uint32_t>(total - lists.size());
  total += lists.size();  // each tile once more, among those with bricks or those without
  // Each tile's kind (WorkSpans): some brick walks, none does, no brick.
  enum TileKind : uint8_t { kMarched, kPlain, kEmpty };
  tile_kinds_.assign(lists.size(), kEmpty);
  uint32_t groups = 0;
  for (size_t t = 0; t < lists.size(); ++t) {
    for (const TileEntry& e : lists[t])
      tile_kinds_[t] = walks[e.brick] ? uint8_t(kMarched) : std::min<uint8_t>(tile_kinds_[t], kPlain);
    if (by_groups && tile_kinds_[t] == kMarched) groups += uint32_t(std::popcount(reached[t]));
  }
  const uint32_t padded_groups = (groups + 7) / 8 * 8;  // whole workgroups of 8 subgroups
  total += padded_groups;
  if (total > capacity) {
    *used = total;  // record_view grows the list to this and builds again
    return out_of_range("render: the view needs " + std::to_string(total) + " tile entries, the frame's work list "
                        "has room for " + std::to_string(capacity) + "; raise the LOD bias or use a smaller image");
  }
  *used = total;
  // Each tile's list.
  uint32_t next = static_cast<uint32_t>(lists.size());
  for (size_t t = 0; t < lists.size(); ++t) {
    dst[t] = glm::uvec4(next, uint32_t(lists[t].size()), 0, 0);
    for (const TileEntry& e : lists[t])
      dst[next++] = glm::uvec4(e.brick, glm::floatBitsToUint(e.depth.x), glm::floatBitsToUint(e.depth.y), 0);
  }
  // Then the tiles as workgroups, by kind, in an order that spreads the
  // image's rows over any contiguous share of a dispatch: lavapipe hands
  // each thread one contiguous share of the workgroups, and in row order
  // one thread took the top of the image, the other the bottom, whatever
  // either held (MRI E-A at step 1: 69.5 ms against 76.8). A row's tiles
  // stay together.
  if (tile_rows_.size() != th) tile_rows_ = interleaved_rows(th);
  for (uint8_t kind : {kMarched, kPlain, kEmpty}) {
    glm::uvec2& span = kind == kMarched ? spans->marched_tiles : kind == kPlain ? spans->plain_tiles : spans->empty_tiles;
    span = glm::uvec2(next, 0);
    for (uint32_t y : tile_rows_)
      for (uint32_t x = 0; x < tw; ++x) {
        if (tile_kinds_[size_t(y) * tw + x] != kind) continue;
        dst[next++] = glm::uvec4(y * tw + x, x * 8, y * 8, 0);
        ++span.y;
      }
  }
  // The marched tiles' reached blocks in the same order, then padding past the image.
  spans->marched_groups = glm::uvec2(next, padded_groups);
  spans->groups_reached = groups;
  if (by_groups) {
    for (uint32_t y : tile_rows_)
      for (uint32_t x = 0; x < tw; ++x) {
        const size_t t = size_t(y) * tw + x;
        if (tile_kinds_[t] != kMarched) continue;
        for (uint32_t g = 0; g < 8; ++g)
          if (reached[t] & (1u << g)) dst[next++] = glm::uvec4(uint32_t(t), x * 8 + 4 * (g & 1), y * 8 + 2 * (g >> 1), 0);
      }
    while (next < spans->marched_groups.x + padded_groups) dst[next++] = glm::uvec4(0, kPastImage, kPastImage, 0);
  }
  return Status::ok();
}

Status BrickRenderer::grow_work_list(size_t entries) {
  const VkDeviceSize bytes = std::max<VkDeviceSize>(items_.size * 2, VkDeviceSize(entries) * sizeof(glm::uvec4));
  if (bytes > ctx_.limits().maxStorageBufferRange)
    return out_of_range("render: the view needs " + std::to_string(entries) + " work-list entries (" +
                        std::to_string(bytes >> 20) + " MiB), more than one storage buffer holds on this device (" +
                        std::to_string(ctx_.limits().maxStorageBufferRange >> 20) +
                        " MiB); raise the LOD bias or use a smaller image");
  VXR_ASSIGN_OR_RETURN(gpu::Buffer grown, gpu::create_buffer(ctx_, {bytes, kWorkListUsage, gpu::MemoryIntent::kUpload,
                                                                    "brick work items"}));
  retired_buffers_.push_back(std::move(items_));
  retired_views_.push_back(std::move(item_texels_));
  items_ = std::move(grown);
  items_used_ = 0;
  VXR_RETURN_IF_ERROR(make_item_texels());
  gpu::write_storage_buffer(ctx_, mono_set_, 6, items_.buffer);  // not bound in a view's frame
  gpu::write_storage_texel_buffer(ctx_, mono_set_, 18, item_texels_.get());
  return Status::ok();
}

Status BrickRenderer::make_item_texels() {
  // All of the list where the device's texel buffers hold it, else a stand-in over its start that no ray reads.
  const uint64_t texels = items_.size / sizeof(glm::uvec4);
  item_texels_fit_ = texels <= ctx_.limits().maxTexelBufferElements;
  VXR_ASSIGN_OR_RETURN(item_texels_, gpu::create_buffer_view(ctx_, items_.buffer, VK_FORMAT_R32G32B32A32_UINT, 0,
                                                             item_texels_fit_ ? items_.size : sizeof(glm::uvec4)));
  return Status::ok();
}

Status BrickRenderer::begin_frame(VkCommandBuffer cmd, const BrickFrameSettings& frame) {
  VXR_TRACE_SCOPE("brick_renderer.begin_frame");
  // Pool changes first, before this frame records anything: a rebuild waits
  // for the device and rebinds the sets; a new timepoint's pins are uploaded
  // through the staging ring this frame's copies then reuse.
  if (apron_wanted_ > pool_->apron()) {
    VXR_RETURN_IF_ERROR(rebuild_pool(apron_wanted_));
    pending_.clear();
  }
  apron_wanted_ = 0;
  VXR_RETURN_IF_ERROR(ensure_timepoint(frame.lod.timepoint));
  retired_.clear();  // the caller waited for the frame that used them
  retired_buffers_.clear();
  retired_views_.clear();
  views_ = 0;
  table_used_ = items_used_ = bits_used_ = 0;
  tf_recorded_ = false;
  requests_.clear();
  std::memset(counters_.mapped, 0, kSampleCounterBytes);
  ++frame_number_;
  pool_->begin_frame();
  last_upload_ = {};
  if (ChunkCache* cache = opt_.stream_from) {
    for (auto& [key, st] : cache->take_errors())
      if (!st) return st;  // the source names the file and the chunk
    if (!pending_.empty()) {
      VXR_ASSIGN_OR_RETURN(last_upload_, pool_->record_upload(cmd, pending_, frame.upload_budget_bytes,
                                                              [cache](const ChunkKey& k) { return cache->get(k); }));
    }
    // This frame's views request what they still miss; the queue holds only that.
    pending_.clear();
    cache->cancel_all();
  }
  return Status::ok();
}

Status BrickRenderer::record_view(VkCommandBuffer cmd, const Camera& camera, const RenderSettings& s,
                                  const BrickFrameSettings& frame, const RenderTarget& target,
                                  BrickFrameStats* stats_out) {
  VXR_TRACE_SCOPE("brick_renderer.record_view");
  const VkRect2D rect = target.rect.extent.width ? target.rect : VkRect2D{{0, 0}, target.extent};
  const uint32_t width = rect.extent.width, height = rect.extent.height;
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  if (rect.offset.x < 0 || rect.offset.y < 0 || rect.offset.x + width > target.extent.width ||
      rect.offset.y + height > target.extent.height)
    return invalid_argument("render: the view's rectangle lies outside its target image");
  if (!(s.step_voxels > 0.0)) return invalid_argument("render: step must be > 0 voxels");
  VXR_RETURN_IF_ERROR(check_brick_settings(s, channels()));
  if (frame.lod.timepoint != pinned_timepoint_)
    return invalid_argument("record_view: timepoint " + std::to_string(frame.lod.timepoint) +
                            " differs from the frame's (begin_frame pinned " + std::to_string(pinned_timepoint_) + ")");
  if (views_ >= opt_.max_views)
    return out_of_range("render: more than " + std::to_string(opt_.max_views) +
                        " views in one frame; raise BrickRendererOptions::max_views");
  // Gradients want an apron of 2; the pool is rebuilt at the next begin_frame
  // (prepare() does it before the first frame), this view reads what it has.
  if (needs_gradients(s) && pool_->apron() < 2) apron_wanted_ = 2;
  const TransferTable tf = build_transfer_table(s);
  VXR_RETURN_IF_ERROR(record_transfer(cmd, tf));
  VXR_RETURN_IF_ERROR(ensure_accum(width, height));
  BrickFrameStats st;
  // Lens warp: traversal, LOD and rays see the full image; the dispatch covers the warped grid.
  const WarpAxis ax = target.warp_x.active() ? target.warp_x : identity_warp(width);
  const WarpAxis ay = target.warp_y.active() ? target.warp_y : identity_warp(height);
  if (ax.warped() != width || ay.warped() != height || (ax.active() && ay.active() && ax.step != ay.step))
    return invalid_argument("render: the lens-warp grid does not match the view's rectangle");
  if (target.under.present() &&
      (target.under.color == VK_NULL_HANDLE || target.under.extent.width != ax.full || target.under.extent.height != ay.full))
    return invalid_argument("render: the underlay (annotations) is " + std::to_string(target.under.extent.width) + "x" +
                            std::to_string(target.under.extent.height) + " with" +
                            (target.under.color ? "" : "out") + " colour; the view needs " + std::to_string(ax.full) +
                            "x" + std::to_string(ay.full) + " with colour");
  const LodView view = view_for(camera, ax.full, ay.full);

  auto t0 = std::chrono::steady_clock::now();
  LodQueries q;
  ChunkStats ranges[VXR_MAX_CHANNELS];
  q.visible = [&](const ChunkKey& key) {
    if (s.model == OpticalModel::kIsosurface && !iso_skips(s)) return true;
    for (uint32_t c = 0; c < channels(); ++c) {
      ChunkKey k = key;
      k.channel = pool_->source_channel(c);
      auto r = src_.stats(k);
      if (!r) return true;  // unknown: draw it
      ranges[c] = *r;
    }
    return brick_may_contribute(s, tf, std::span(ranges, channels()));
  };
  q.resident = [this](const ChunkKey& k) { return pool_->resident(k); };
  LodResult lod = traverse_lod(src_, view, frame.lod, q);
  st.traverse_ms = ms_since(t0);
  st.lod = lod.stats;

  // This view's slices of the frame's table and work list (offsets aligned for descriptors).
  // 16 bytes at least: the records' first texel (binding 15) is the offset / 16.
  const VkDeviceSize salign = std::max<VkDeviceSize>(ctx_.limits().minStorageBufferOffsetAlignment, 16);
  const VkDeviceSize table_base = align_up(table_used_, salign);
  const VkDeviceSize table_bytes = std::max<size_t>(lod.draw.size(), 1) * sizeof(shader::BrickRecord);
  if (table_base + table_bytes > table_.size)
    return out_of_range("render: the view needs " + std::to_string(lod.draw.size()) + " bricks, the frame's brick "
                        "table has room for " + std::to_string((table_.size - std::min(table_.size, table_base)) /
                                                               sizeof(shader::BrickRecord)) +
                        " (of " + std::to_string(opt_.max_bricks) + "); raise the LOD bias or max_bricks");
  // Where skipping jumps empty cells, rays march only the box of a brick's
  // kept cells (every model but an average over whole bricks, below, and
  // iso only where iso_skips), and the work lists cover only its screen
  // rectangle: the same image, without the empty margin.
  const bool skip_cells = frame.lod.skip_empty && frame.skip_cells;
  const bool classified = s.model != OpticalModel::kIsosurface || iso_skips(s);
  std::optional<CellOpacity> cell_opacity;
  if (skip_cells && classified) cell_opacity.emplace(s, tf, value_scales_);
  // An average whose table shows entry 0 must cast every ray that meets
  // the volume (a ray that takes nothing shows entry 0 too): its bricks
  // march whole, and are listed wherever their rays go. Without cells
  // nothing is skipped, so every ray is cast anyway.
  const bool whole_bricks = cell_opacity && cell_opacity->marches_whole_bricks();
  std::vector<BrickBox>& march_world = march_world_;  // reused: no allocation per view once sizes settle
  std::vector<uint8_t>& walks = walks_;
  march_world.resize(lod.draw.size());
  walks.resize(lod.draw.size());
  blocks_.assign(lod.draw.size(), glm::uvec2(0));
  block_world_.clear();
  // A brick whose box keeps every cell is marched without a cell walk: the
  // walk would find no empty cell (dense 256^3 E-A, `vxr bench roofline`:
  // 0.87 against 1.29-1.33 ms of marching per million samples). A brick with
  // any empty cell walks: skipping them paid at every step measured, even
  // where they are a few percent of the box (one-channel MinIP: see
  // minip_walk_pays below). MIP / MinIP always walk: their
  // cells empty with the running value.
  uint64_t split = 0, groups = 0;
  const bool reduce = s.model == OpticalModel::kMip || s.model == OpticalModel::kMinIp;
  CellFacts minip;  // one-channel MinIP: the walked bricks' lowest_max and minima together
  for (size_t i = 0; i < lod.draw.size(); ++i) {
    const ChunkKey& key = lod.draw[i];
    const glm::uvec3 o = pool_->touch(key);
    // Cells skip by ranges that hold within VXR_CELL_BAND of each cell. A
    // brick whose eye lies kCellEyeLimit or more of its voxels away has its
    // samples' and walks' positions rounded too coarsely for that (a few
    // ulps of 8192 are 0.004 voxel): it marches its whole box, without a walk.
    const auto& ds_u = src_.levels()[key.level].downsample;
    const glm::dvec3 ds(ds_u[0], ds_u[1], ds_u[2]), origin = chunk_box(src_, key).lo;
    const glm::dvec3 local_eye = (view.eye - origin) / ds;
    const bool near = glm::all(glm::lessThan(glm::abs(local_eye), glm::dvec3(kCellEyeLimit)));
    CellFacts facts;
    const std::vector<BrickBox>* kept_blocks = nullptr;  // march_box's cache: valid until its next call
    const BrickBox local = march_box(key, frame.lod, cell_opacity && near ? &*cell_opacity : nullptr, &facts,
                                     opt_.tile_depths ? &kept_blocks : nullptr);
    // Average over whole bricks: a brick with no kept cell is listed, takes no sample.
    const bool no_samples = whole_bricks && near && facts.none_kept;
    const bool walk = near && !no_samples && (reduce || !(whole_bricks ? facts.every_kept : facts.all_kept));
    if (kept_blocks && walk) {
      blocks_[i].x = static_cast<uint32_t>(block_world_.size());
      for (const BrickBox& b : *kept_blocks) {
        const BrickBox v{glm::max(local.lo, b.lo), glm::min(local.hi, b.hi)};  // within the march box (ROI)
        if (!is_empty(v)) block_world_.push_back({origin + v.lo * ds, origin + v.hi * ds});
      }
      blocks_[i].y = static_cast<uint32_t>(block_world_.size());
    }
    walks[i] = walk;
    fill_record(static_cast<uint8_t*>(table_.mapped) + table_base + i * sizeof(shader::BrickRecord), key,
                glm::vec3(o), view, frame.lod, local, walk, no_samples);
    if (cell_opacity && walk) {  // only walked bricks weigh in the choice of cells or groups below
      split += facts.split;
      groups += facts.boxed_groups;
      ++st.bricks_walked;
      if (s.model == OpticalModel::kMinIp) {
        minip.lowest_max = std::min(minip.lowest_max, facts.lowest_max);
        for (uint32_t b = 0; b < kMinIpBins; ++b) minip.minima[b] += facts.minima[b];
      }
    }
    march_world[i] = {origin + local.lo * ds, origin + local.hi * ds};
  }
  // kAuto: tiled on every device, as measured (brick_renderer.h).
  BrickPassMode mode = frame.mode != BrickPassMode::kAuto ? frame.mode : BrickPassMode::kTiled;
  // Waves carry a ray's state in one RGBA32F texel; larger states march tiled.
  if (mode == BrickPassMode::kMultipass && !brick_state_fits_texel(s, channels())) mode = BrickPassMode::kTiled;
  VkDeviceSize items_base = align_up(items_used_, salign);
  size_t items_capacity = 0, items_n = 0;
  WorkSpans spans;
  // The marched tiles as the 4x2 blocks some entry reaches, where one block
  // is one subgroup and a block left out holds what its rays would finish
  // as: E-A and emission rays that meet only empty cells, in a view that
  // record_cast clears first.
  const bool by_groups = opt_.group_lists && skip_cells && ctx_.info().subgroup_size == 8 &&
                         (s.model == OpticalModel::kEmissionAbsorption || s.model == OpticalModel::kEmission ||
                          (s.model == OpticalModel::kAverage && !whole_bricks) ||
                          (s.model == OpticalModel::kIsosurface && iso_skips(s))) &&
                         clears_tiled_view(target, width, height);
  auto build_work = [&]() -> Status {
    items_capacity = items_base < items_.size ? (items_.size - items_base) / sizeof(glm::uvec4) : 0;
    auto* dst = reinterpret_cast<glm::uvec4*>(static_cast<uint8_t*>(items_.mapped) + items_base);
    items_n = 0;
    if (mode == BrickPassMode::kMultipass) {
      VXR_ASSIGN_OR_RETURN(spans.waves, build_waves(march_world, view, ax, ay, dst, items_capacity, &items_n));
    } else if (mode == BrickPassMode::kTiled) {
      VXR_RETURN_IF_ERROR(build_tile_lists(march_world, walks, blocks_, block_world_, view, ax, ay, by_groups,
                                           whole_bricks, dst, items_capacity, &items_n, &spans));
    }
    return Status::ok();
  };
  Status built = build_work();
  if (!built.is_ok() && items_n > items_capacity) {  // a larger image or more bricks than the list has room for
    VXR_RETURN_IF_ERROR(grow_work_list(items_n));
    items_base = 0;
    built = build_work();
  }
  VXR_RETURN_IF_ERROR(built);
  st.tile_entries = spans.tile_entries;
  st.tile_blocks = spans.blocks;
  st.tiles_plain = spans.plain_tiles.y;
  st.tiles_empty = spans.empty_tiles.y;
  const VkDeviceSize items_bytes = std::max<size_t>(items_n, 1) * sizeof(glm::uvec4);
  if (items_base + items_bytes > items_.size) return out_of_range("render: the frame's work list is full");
  const uint64_t wanted = lod.stats.drawn - lod.stats.fallback + lod.stats.missing;
  st.hit_rate = wanted ? double(lod.stats.drawn - lod.stats.fallback) / double(wanted) : 1.0;

  shader::RaycastParams params =
      pack_params(plan_raycast(camera, s, placement(), value_scales_, ax.full, ay.full), false);
  params.control.y = width;  // the rays dispatched (the warped grid's)
  params.control.z = height;
  set_clip(params, s, frame.lod);
  const VkDeviceSize params_offset = VkDeviceSize(views_) * params_stride_;
  std::memcpy(static_cast<uint8_t*>(params_.mapped) + params_offset, &params, sizeof(params));

  VkDescriptorSet set = view_sets_[views_];
  const bool direct = target.storage_view != VK_NULL_HANDLE && target.format == VK_FORMAT_R8G8B8A8_UNORM;
  gpu::write_storage_image(ctx_, set, 2, direct ? target.storage_view : target_.view.get());
  gpu::write_storage_image(ctx_, set, 3, accum_.view);
  gpu::write_storage_image(ctx_, set, 9, target.under.present() ? target.under.depth : no_under_depth_.view.get());
  gpu::write_storage_image(ctx_, set, 10, target.under.present() ? target.under.color : no_under_color_.view.get());
  gpu::write_storage_buffer(ctx_, set, 4, table_.buffer, table_bytes, table_base);
  gpu::write_storage_buffer(ctx_, set, 6, items_.buffer, items_bytes, items_base);
  gpu::write_storage_texel_buffer(ctx_, set, 18, item_texels_.get());
  spans.list_texel = static_cast<uint32_t>(items_base / sizeof(glm::uvec4));
  gpu::write_uniform_buffer(ctx_, set, 7, params_.buffer, sizeof(shader::RaycastParams), params_offset);
  // This view's region of the cell bits (the finest walk's size): the rays
  // index it by their record, and it outlives the frame for the next one's.
  const VkDeviceSize bits_base = align_up(bits_used_, cell_bits_align());
  const VkDeviceSize bits_bytes = std::max<size_t>(lod.draw.size(), 1) * cell_bits_bytes(pool_->cells());
  gpu::write_storage_buffer(ctx_, set, 13, cell_bits_.buffer, bits_bytes, bits_base);
  gpu::write_uniform_buffer(ctx_, set, 14, cell_bits_.buffer, cell_bits_window_bytes(bits_base), bits_base);
  // E-A and emission walk the pool's cells or 2x2x2 groups of them,
  // whichever is cheaper by a rough count: the cells let a ray skip the
  // samples of the empty cells in groups it would march (cell size / step
  // each), the groups take one walk step per group crossed instead of about
  // two, weighed alike (the DDA walk costs about a third of a sample a cell;
  // the weights date from the walk before it). The MRI walks cells up to
  // step 2, the sparse vessels up to step 1 (`vxr bench peer`); a dense
  // volume's bricks keep every cell and do not walk (`vxr bench roofline`).
  CellWalk walk = CellWalk::kOff;
  CellClassInputs& classify = classify_scratch_;  // reused: no allocation per frame once sizes settle
  if (skip_cells) {
    classify.records.clear();
    for (const ChunkKey& key : lod.draw) classify.records.emplace_back(key, pool_->slot_of(key));
    std::copy(std::begin(params.window), std::end(params.window), classify.window.begin());
    classify.table.assign(tf.rgba.begin(), tf.rgba.end());
    classify.iso = s.model == OpticalModel::kIsosurface ? glm::vec2(params.iso.x, float(params.control2.y)) : glm::vec2(0.0f);
    classify.bits_offset = bits_base;
    classify.bits_bytes = bits_bytes;
    const double skipped = double(split) * pool_->cells().cell_size / s.step_voxels;
    walk = pool_->cells().cell_size < 4 && skipped > double(groups) ? CellWalk::kCells : CellWalk::kGroups;
    if (opt_.cell_walk != BrickCellWalk::kAuto)
      walk = opt_.cell_walk == BrickCellWalk::kCells ? CellWalk::kCells : CellWalk::kGroups;
    if (s.model == OpticalModel::kMinIp && channels() == 1 && !minip_walk_pays(minip)) walk = CellWalk::kOff;
  }
  VXR_RETURN_IF_ERROR(record_cast(cmd, set, s, params.control.x, width, height, static_cast<uint32_t>(lod.draw.size()),
                                  table_base, reads_of(pool_->atlas(), pool_->atlas_texels_view() != nullptr), mode,
                                  spans, target, walk, frame.sample_work, &classify, &st));
  ++views_;
  table_used_ = table_base + table_bytes;
  items_used_ = items_base + items_bytes;
  bits_used_ = bits_base + bits_bytes;

  // Missing bricks: streaming asks the loader threads (nearest first, this
  // frame before older ones); otherwise render() reads them after the frame.
  if (ChunkCache* cache = opt_.stream_from) {
    std::vector<ChunkKey> chunks;
    for (size_t i = 0; i < lod.requests.size(); ++i) {
      chunks.clear();
      pool_->slot_chunks(lod.requests[i], chunks);  // every channel, and neighbours for a wider apron
      for (const ChunkKey& k : chunks) cache->request(k, double(frame_number_) * 1e7 - double(i));
      pending_.push_back(lod.requests[i]);
    }
    st.bricks_uploaded = last_upload_.bricks;
    st.bytes_uploaded = last_upload_.bytes;
    st.evicted = last_upload_.evicted;
  } else {
    requests_.insert(requests_.end(), lod.requests.begin(), lod.requests.end());
  }
  if (stats_out) *stats_out = st;
  return Status::ok();
}

Result<ImageRgba8> BrickRenderer::render(const Camera& camera, const RenderSettings& s,
                                         const BrickFrameSettings& frame, uint32_t width, uint32_t height,
                                         BrickFrameStats* stats_out, const UnderlayRecorder& underlay) {
  ImageRgba8 img;
  VXR_RETURN_IF_ERROR(render_into(img, camera, s, frame, width, height, stats_out, underlay));
  return img;
}

Status BrickRenderer::render_into(ImageRgba8& out, const Camera& camera, const RenderSettings& s,
                                  const BrickFrameSettings& frame, uint32_t width, uint32_t height,
                                  BrickFrameStats* stats_out, const UnderlayRecorder& underlay) {
  VXR_TRACE_SCOPE("brick_renderer.render");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  VXR_RETURN_IF_ERROR(ensure_target(width, height));
  VXR_RETURN_IF_ERROR(draw_and_wait(camera, s, frame,
                                    {target_.image, target_.view, target_.format, {width, height}, VK_IMAGE_LAYOUT_GENERAL},
                                    stats_out, underlay));
  if (out.width != width || out.height != height) out = ImageRgba8(width, height);
  return readback_.read(ctx_, target_, out.pixels.data(), out.pixels.size());
}

Result<ImageRgbaF> BrickRenderer::render_float(const Camera& camera, const RenderSettings& s,
                                               const BrickFrameSettings& frame, uint32_t width, uint32_t height,
                                               BrickFrameStats* stats_out, const UnderlayRecorder& underlay) {
  VXR_TRACE_SCOPE("brick_renderer.render_float");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  VXR_RETURN_IF_ERROR(ensure_target(width, height));  // bound (unwritten) while the float target is drawn
  if (!float_target_.image || float_target_.extent.width != width || float_target_.extent.height != height) {
    if (float_target_.image) retired_.push_back(std::move(float_target_));
    VXR_ASSIGN_OR_RETURN(float_target_,
                         gpu::create_image(ctx_, {VK_IMAGE_TYPE_2D, VK_FORMAT_R32G32B32A32_SFLOAT, {width, height, 1},
                                                  // storage: only so the image may have a view
                                                  VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                      VK_IMAGE_USAGE_STORAGE_BIT,
                                                  "brick raycast float target"}));
    VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
      gpu::transition_image(cmd, float_target_, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_BLIT_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    }));
  }
  // Not RGBA8: the final float pixels are blitted (nearest, same size: copied exactly) into it.
  VXR_RETURN_IF_ERROR(draw_and_wait(
      camera, s, frame,
      {float_target_.image, VK_NULL_HANDLE, float_target_.format, {width, height}, VK_IMAGE_LAYOUT_GENERAL}, stats_out,
      underlay));
  ImageRgbaF img{width, height, std::vector<float>(size_t(width) * height * 4)};
  VXR_RETURN_IF_ERROR(readback_.read(ctx_, float_target_, img.rgba.data(), img.rgba.size() * sizeof(float)));
  return img;
}

Status BrickRenderer::draw_and_wait(const Camera& camera, const RenderSettings& s, const BrickFrameSettings& frame,
                                    RenderTarget target, BrickFrameStats* stats_out, const UnderlayRecorder& underlay) {
  VXR_RETURN_IF_ERROR(check_brick_settings(s, channels()));
  VXR_RETURN_IF_ERROR(prepare(s));
  BrickFrameStats st;
  Status recorded = Status::ok();
  const auto t0 = std::chrono::steady_clock::now();
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    if (timestamps_) {
      vkCmdResetQueryPool(cmd, timestamps_, 0, 2);
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, timestamps_, 0);
    }
    recorded = begin_frame(cmd, frame);
    if (recorded && underlay) {
      auto under = underlay(cmd);
      if (under) target.under = *under;
      else recorded = under.status();
    }
    if (recorded) recorded = record_view(cmd, camera, s, frame, target, &st);
    if (timestamps_) vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT, timestamps_, 1);
  }));
  VXR_RETURN_IF_ERROR(recorded);
  if (timestamps_) {
    uint64_t ticks[2] = {0, 0};
    if (VkResult vr = vkGetQueryPoolResults(ctx_.device(), timestamps_, 0, 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                            VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
        vr != VK_SUCCESS)
      return internal_error("brick renderer: vkGetQueryPoolResults failed (" + std::to_string(int(vr)) + ")");
    st.gpu_ms = double(ticks[1] - ticks[0]) * ctx_.timestamp_period_ns() * 1e-6;
  }
  st.render_ms = ms_since(t0) - st.traverse_ms;
  st.samples = sum_sample_counters(counters_.mapped);
  // Uploads after the frame's rays: what arrives is drawn from the next frame on.
  if (!requests_.empty()) {
    VXR_ASSIGN_OR_RETURN(UploadStats up, pool_->upload(requests_, frame.upload_budget_bytes));
    st.bytes_uploaded = up.bytes;
    st.bricks_uploaded = up.bricks;
    st.evicted = up.evicted;
  }
  if (stats_out) *stats_out = st;
  return Status::ok();
}

Status BrickRenderer::set_monolithic(uint32_t level, uint32_t timepoint) {
  if (level >= src_.levels().size()) return invalid_argument("monolithic: no level " + std::to_string(level));
  if (timepoint >= src_.info().timepoints)
    return invalid_argument("monolithic: no timepoint " + std::to_string(timepoint));
  if (level == mono_level_ && timepoint == mono_timepoint_) return Status::ok();
  const LevelInfo& li = src_.levels()[level];
  const uint32_t max3d = ctx_.limits().maxImageDimension3D;
  for (uint64_t d : li.dims)
    if (d > max3d)
      return out_of_range("monolithic: level " + std::to_string(level) + " has a side of " + std::to_string(d) +
                          " voxels, past the device's 3D texture limit of " + std::to_string(max3d));
  const DType dtype = src_.info().dtype;
  const VkFormat format = brick_texel_format(dtype);
  const uint32_t sb = dtype_bytes(dtype), tb = gpu::format_texel_bytes(format);
  const uint64_t nx = li.dims[0], ny = li.dims[1], nz = li.dims[2];
  const uint32_t cs = src_.chunk_size(), a = src_.apron(), e = cs + 2 * a;
  std::vector<gpu::Image> textures;
  std::vector<gpu::ImageTexels> views;
  const uint32_t word_width = texel_word_width(format);
  const VkExtent3D plain{uint32_t(nx), uint32_t(ny), uint32_t(nz)},
      wide{uint32_t(nx) * std::max(word_width, 1u), plain.height, plain.depth};
  const VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  // Read as the pool's atlases are (by hand through texel views of texel
  // words, or sampled), so both paths agree; sampled where that does not fit.
  const bool by_hand = pool_->atlas_texels_view() != nullptr;
  // Every channel's texture and, read by hand, its view; false where the
  // words get no view (the driver's padded rows outgrow one).
  const auto build = [&](bool words) -> Result<bool> {
    views.clear();  // before the textures whose memory they view
    textures.clear();
    const VkExtent3D extent = words ? wide : plain;
    for (uint32_t c = 0; c < channels(); ++c) {
      std::vector<uint8_t> dense(nx * ny * nz * sb);  // native voxels, then converted like the pool's
      for (uint32_t cz = 0; cz < li.chunk_counts[2]; ++cz)
        for (uint32_t cy = 0; cy < li.chunk_counts[1]; ++cy)
          for (uint32_t cx = 0; cx < li.chunk_counts[0]; ++cx) {
            VXR_ASSIGN_OR_RETURN(auto chunk, src_.read({level, cx, cy, cz, pool_->source_channel(c), timepoint}));
            for (uint32_t z = 0; z < cs && uint64_t(cz) * cs + z < nz; ++z)
              for (uint32_t y = 0; y < cs && uint64_t(cy) * cs + y < ny; ++y) {
                const uint64_t gx = uint64_t(cx) * cs, gy = uint64_t(cy) * cs + y, gz = uint64_t(cz) * cs + z;
                const uint64_t n = std::min<uint64_t>(cs, nx - gx);
                std::memcpy(&dense[((gz * ny + gy) * nx + gx) * sb],
                            &chunk->data[((uint64_t(z + a) * e + (y + a)) * e + a) * sb], n * sb);
              }
          }
      std::vector<uint8_t> texels(nx * ny * nz * tb);
      convert_to_texels(dtype, dense.data(), nx * ny * nz, texels.data());
      if (words) {
        const uint64_t row = nx * tb;
        std::vector<uint8_t> rows(texels.size() * word_width);
        for (uint64_t r = 0; r < ny * nz; ++r) {
          const uint8_t* from = &texels[r * row];
          write_texel_words(format, from, (r + 1) % ny != 0 ? from + row : from, uint32_t(nx), &rows[r * row * word_width]);
        }
        texels = std::move(rows);
      }
      gpu::ImageCreateInfo ii{VK_IMAGE_TYPE_3D, format, extent, usage, "monolithic volume"};
      ii.host_mapped = words;
      VXR_ASSIGN_OR_RETURN(gpu::Image tex, gpu::create_image(ctx_, ii));
      VXR_RETURN_IF_ERROR(gpu::upload_image(ctx_, tex, texels.data(), texels.size()));
      if (words) {
        // Words are only read through views, whose pitches are whole words;
        // a sampler would read them as texels.
        if (tex.row_pitch % 4 != 0 || tex.depth_pitch % 4 != 0) return false;
        Result<gpu::ImageTexels> view = gpu::create_image_texels(ctx_, tex, kAtlasTexelElement);
        if (!view.is_ok()) return false;
        views.push_back(std::move(*view));
      }
      textures.push_back(std::move(tex));
    }
    return true;
  };
  const bool words = by_hand && pool_->texel_words() && wide.width <= max3d &&
                     gpu::host_mapped_image_supported(ctx_, VK_IMAGE_TYPE_3D, format, usage, wide);
  bool built = false;
  VXR_ASSIGN_OR_RETURN(built, build(words));
  if (!built) {
    VXR_ASSIGN_OR_RETURN(built, build(false));  // the texels as they are, sampled
  }
  if (views.size() != textures.size()) views.clear();  // every channel by hand, or none
  mono_texels_.clear();  // before the textures whose memory they view
  mono_tex_ = std::move(textures);
  mono_texels_ = std::move(views);
  bind_atlases(mono_set_, mono_atlases());
  mono_level_ = level;
  mono_timepoint_ = timepoint;
  return Status::ok();
}

Result<ImageRgba8> BrickRenderer::render_monolithic(const Camera& camera, const RenderSettings& s,
                                                    const LodSettings& clip, uint32_t width, uint32_t height,
                                                    BrickFrameStats* stats_out) {
  VXR_TRACE_SCOPE("brick_renderer.render_monolithic");
  if (mono_level_ == UINT32_MAX) return invalid_argument("render_monolithic: call set_monolithic first");
  if (width == 0 || height == 0) return invalid_argument("render: image size has a zero side");
  VXR_RETURN_IF_ERROR(check_brick_settings(s, channels()));
  VXR_RETURN_IF_ERROR(ensure_target(width, height));
  VXR_RETURN_IF_ERROR(ensure_accum(width, height));
  const LodView view = view_for(camera, width, height);
  // One "brick": the whole level, local origin at voxel 0, no apron (the
  // sampler's clamp-to-edge repeats the border voxels like an apron would).
  const LevelInfo& li = src_.levels()[mono_level_];
  const auto& ds_u = li.downsample;
  const glm::dvec3 ds(ds_u[0], ds_u[1], ds_u[2]);
  const glm::dvec3 dims0(src_.info().dims[0], src_.info().dims[1], src_.info().dims[2]);
  glm::dvec3 lo(0.0), hi = dims0 / ds;
  if (clip.roi.enabled) {
    lo = glm::max(lo, clip.roi.lo / ds);
    hi = glm::min(hi, clip.roi.hi / ds);
  }
  shader::BrickRecord r{};
  r.eye = v4(view.eye / ds);
  r.scale = v4(1.0 / ds);
  r.box_lo = v4(lo);
  r.box_hi = v4(hi);
  r.atlas = glm::vec4(0.0f, 0.0f, 0.0f, -1.0f);  // w < 0: no cell ranges
  if (clip.cut.enabled) {
    const glm::dvec3 n = clip.cut.normal * ds;
    const double len = glm::length(n);
    if (len > 0) r.plane = v4(n / len, clip.cut.offset / len);
  }
  BrickFrameStats st;
  st.lod.drawn = 1;
  shader::RaycastParams params = pack_params(plan_raycast(camera, s, placement(), value_scales_, width, height), false);
  set_clip(params, s, clip);
  const RenderTarget target{target_.image, target_.view, target_.format, {width, height}, VK_IMAGE_LAYOUT_GENERAL};
  Status recorded = Status::ok();
  const auto t0 = std::chrono::steady_clock::now();
  VXR_RETURN_IF_ERROR(ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
    BrickFrameSettings frame;  // the pool's timepoint stays as it is (the texture has its own)
    frame.lod.timepoint = pinned_timepoint_;
    recorded = begin_frame(cmd, frame);
    if (recorded) recorded = record_transfer(cmd, build_transfer_table(s));
    if (!recorded) return;
    std::memcpy(table_.mapped, &r, sizeof(r));
    std::memcpy(params_.mapped, &params, sizeof(params));
    gpu::write_storage_image(ctx_, mono_set_, 2, target_.view);
    gpu::write_storage_image(ctx_, mono_set_, 3, accum_.view);
    recorded = record_cast(cmd, mono_set_, s, params.control.x, width, height, 1, 0,
                           reads_of(mono_tex_.at(0), !mono_texels_.empty()), BrickPassMode::kSinglePass, {}, target,
                           CellWalk::kOff, SampleWork::kShade, nullptr, &st);
  }));
  VXR_RETURN_IF_ERROR(recorded);
  st.render_ms = ms_since(t0);
  st.samples = sum_sample_counters(counters_.mapped);
  ImageRgba8 img(width, height);
  VXR_RETURN_IF_ERROR(readback_.read(ctx_, target_, img.pixels.data(), img.pixels.size()));
  if (stats_out) *stats_out = st;
  return img;
}

}  // namespace vxr

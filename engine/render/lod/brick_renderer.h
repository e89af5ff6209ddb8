// Out-of-core volume rendering: LOD traversal -> brick pool -> brick ray caster.
//
// One render() is one eye's frame: traverse the octree in double (culling,
// LOD, empty-space skip, front-to-back order, parent fallback), write the
// brick table (brick-local eye, scale, clip box, cut plane, atlas origin),
// upload missing bricks within the frame's byte budget, march, read back.
//
// Pass modes. kSinglePass: one dispatch; each ray loops over the whole brick
// table with a slab test per brick. kMultipass (the paper's, batched): each
// brick becomes work items, one per 8x8 pixel tile its screen rectangle
// touches; items go into waves so that no two items of a wave share a tile,
// and one dispatch per wave continues the rays from an RGBA32F accumulation
// image. Measured with `vxr bench lod` (docs/ARCHITECTURE.md): on lavapipe the
// single pass is ~10x slower (every ray pays for every brick), and one
// dispatch per brick (the paper's literal multipass) pays a dispatch and a
// barrier per brick; waves need about as many dispatches as bricks overlap
// along a ray. kTiled: one dispatch; each 8x8 tile walks its own front-to-back
// list of the bricks its screen rectangle touches. All three give the same
// image. kAuto (the default) is tiled on every device, as measured: on
// lavapipe (`vxr bench lod`, 256^3 sparse vessels, 256x256) tiled 7.4 ms vs
// multipass 9.9 vs single 64.8, and `vxr bench peer` (512x512) tiled 10-40%
// faster than the waves in every scene, whose items each load and store the
// ray's state; on an H100 tiled 2.0 ms, single 1.7, multipass 3.1 (all 512
// bricks drawn: tiled 1.9 ms vs multipass 7.9, where waves cost a dispatch
// and a barrier each and the GPU idles between them).
//
// Empty space is skipped three ways, with identical images: the traversal
// drops bricks whose min/max maps to zero opacity (brick_may_contribute);
// rays march only the box of a brick's cells that may change a ray
// (CellOpacity, march_box; an average whose table shows entry 0 marches
// whole bricks, and iso needs iso_back_sample), and the work lists cover only
// that box's screen rectangle; rays jump the empty cells (~4^3 voxels,
// BrickCells) inside it, on the same sample grid. LodSettings::skip_empty
// turns all off, BrickFrameSettings::skip_cells the boxes and cells (`vxr
// bench peer` measures).
// Early ray termination: emission-absorption rays stop at transmittance
// RenderSettings::early_termination, in every pass mode.
//
// render_monolithic() is the comparison path: one level of the source as a
// single 3D texture, drawn by the same shader as one brick.
//
// Classification and compositing are the GLSL core
// (shaders_glsl/include/raycast_core.glsl, RaycastParams, the transfer
// table); see check_brick_settings for what it draws. Volumes already in
// memory are its one-brick (or few-brick) case: render/lod/memory_volume.h.
// The timepoint is the frame's (BrickFrameSettings::lod.timepoint, pinned by
// begin_frame, so every view of a frame shares it); channels are the pool's
// (BrickPoolOptions::channels).
#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "core/image.h"
#include "core/status.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "gpu/resources.h"
#include "render/camera.h"
#include "render/lod/brick_pool.h"
#include "render/lod/lod_traversal.h"
#include "render/transfer_function.h"
#include "render/volume_renderer.h"
#include "shared/raycast_params.h"
#include "volume/chunk_cache.h"

namespace vxr {

// Compiled variants of the brick shader (keyed by their specialisation
// constants' values, BrickRenderer::ShaderVariant). Renderers on one gpu::Context may
// share them: lavapipe compiles each variant on the CPU, which dominates
// creating a renderer for a small volume (tests, the stability suite).
inline constexpr size_t kVariantConstants = 17;  // brick_raycast.comp's ids 100..116
using VariantKey = std::array<uint32_t, kVariantConstants>;
struct BrickPipelines {
  std::map<VariantKey, gpu::ComputePipeline> variants;
};

// Which cells E-A and emission rays walk where the pool's are 2 voxels: the
// cells or 2x2x2 groups of them, by record_view's count per frame (kAuto), or
// fixed (tests pin that both give the image without skipping).
enum class BrickCellWalk { kAuto, kCells, kGroups };

struct BrickRendererOptions {
  BrickPoolOptions pool;
  uint32_t max_bricks = 16384;         // brick-table capacity per frame (all views together)
  uint32_t max_work_items = 1u << 20;  // multipass / tile-list entries per frame (all views together); grows as needed
  uint32_t max_views = 32;             // record_view calls per frame (one per eye)
  // Streaming (vxr view): missing bricks are requested from this cache,
  // whose loader threads read and decode them; begin_frame copies in those
  // that have arrived. A frame never waits for I/O: until a brick arrives its
  // resident ancestor is drawn. Null: render() reads missing bricks itself
  // after the frame (vxr render, tests). Must outlive the renderer.
  ChunkCache* stream_from = nullptr;
  // Small volumes: when every chunk of every level (channel 0, timepoint 0)
  // fits in half the pool, upload and pin them all at create(), so every
  // frame draws at full detail from the first (and deterministically).
  bool preload_if_fits = false;
  // The E-A and emission cell tests read each cell's emptiness
  // bit through a uniform buffer while the view's bricks fit its range (64
  // KiB: 128 bricks of 64^3 in 4-voxel cells, 16 in 2-voxel ones), else
  // through a storage buffer. False: always the storage buffer (tests pin
  // that both agree).
  bool uniform_cell_bits = true;
  // The rays read the brick records and their work list as texels of the
  // brick table and the list's buffer where the device's texel buffers hold
  // both, else through storage buffers. False: always the storage buffers.
  bool texel_brick_records = true;
  // MIP / MinIP cell tests read the keys as texels of a uniform texel
  // buffer where the device holds them all, else from the storage buffer.
  // False: always the storage buffer.
  bool texel_cell_keys = true;
  // Tiled frames: each tile's entry for a walked brick carries the view
  // depths where the tile's rays can meet its kept cells' blocks, and a tile
  // whose rays meet none drops the brick (build_tile_lists). False: every brick on every tile of
  // its screen rectangle, marched over its whole box (tests pin the image).
  bool tile_depths = true;
  // Tiled frames: the tiles no brick touches hold what an empty ray
  // finishes as, (0, 0, 0, 0) or opaque black. Where the view has no
  // underlay and is its whole image (or draws into the accumulation image),
  // one clear writes them instead of a dispatch of the variant without bricks.
  // False: always the dispatch (tests pin that both agree).
  bool clear_empty_tiles = true;
  // Tiled E-A and emission frames where a subgroup is 8 invocations
  // (lavapipe at 256 bits), cleared as above: the tiles with a walked brick
  // are dispatched as the 4x2 pixel blocks (one subgroup each) whose rays
  // can meet a brick's kept blocks, so a block whose rays would all find
  // nothing costs nothing. False: whole tiles (tests pin that both agree).
  bool group_lists = true;
  // Where every channel's colour map is one hue times a value (gray, red,
  // ..., yellow: TransferTable::hue), E-A and emission rays look a sample up in one texel
  // of that factored table instead of two of the table itself, and additive
  // E-A sums one value per channel instead of an RGB colour: the same floats,
  // about 6% of the MRI's E-A frame on lavapipe. False: always the table
  // (tests pin that both agree).
  bool hue_tables = true;
  // The most blocks one view projects for them (each costs a screen
  // rectangle and its tiles on the CPU, about 250 ns on lavapipe's 2-core
  // host: 2 ms a view); bricks past it march their whole box.
  uint32_t max_tile_blocks = 8192;
  BrickCellWalk cell_walk = BrickCellWalk::kAuto;
  // Shared with other renderers on the same context (they must outlive none
  // of its frames); null: this renderer's own.
  std::shared_ptr<BrickPipelines> pipelines;
};

// The brick shader classifies and composites with the GLSL core
// (raycast_core.glsl): every optical model (ea, emission, mip, minip,
// average, iso), 1-4 channels (additive or composite), any transfer function,
// gradient opacity, depth colour, any sample offset and per-pixel jitter (on
// a step grid anchored at the eye, so bricks continue each other). Settings
// no renderer draws are refused, kInvalidArgument naming the setting.
// `channels`: how many channels the renderer draws.
Status check_brick_settings(const RenderSettings& s, uint32_t channels = 1);

// Empty-space test for a brick whose payload values (data units, apron
// included) lie in ranges[c] for drawn channel c, given the settings and their
// transfer table: false only when skipping the brick cannot change any pixel.
// Per model:
//  - ea, emission: every enabled channel's table entries the interpolation can
//    reach over its windowed range have zero opacity (gradient opacity only
//    scales opacity down; depth colour changes colour, not opacity).
//  - mip: every enabled channel's range is at or below its window's low end
//    (windowed 0 never raises the running maximum) and every enabled channel's
//    entry 0 is transparent (a ray whose every brick was skipped shows nothing,
//    one that took samples shows the table at its maximum).
//  - minip: the mirror image: every range at or above the window's high end
//    (windowed 1 never lowers the running minimum) and entry 255 transparent.
//  - average: every enabled channel's range windows to 0 exactly (clearly
//    below the window's low end, or nothing above 0 under a window from 0
//    up) and no enabled channel's entry 0 is opaque (average_shows_zero: a
//    ray whose every brick was skipped shows nothing). The rays count the
//    length they average over from their chord (brick_raycast.comp
//    region_chord), not from the bricks they march.
//  - iso: the iso channel's range reaches the iso value (below it no sample
//    can cross), where iso_back_sample holds; otherwise never (a crossing is
//    then refined against the sample the ray carried, which a skip would lose).
bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, std::span<const ChunkStats> ranges);
// Average: whether an enabled channel's table entry 0 is opaque, so a ray
// that takes nothing but meets the volume shows it: such a view skips no
// brick and casts every ray over whole bricks (cells are still skipped).
bool average_shows_zero(const RenderSettings& s, const TransferTable& table);
// One channel: ranges = {[lo, hi]}.
bool brick_may_contribute(const RenderSettings& s, const TransferTable& table, double lo, double hi);

// The longest step (voxels of the marched level) at which an isosurface
// crossing is refined against the sample one step back read again from the
// crossing's brick (brick_raycast.comp iso_crossing): the atlas slots' apron
// of 2 voxels holds it. Then the crossing does not depend on what the ray
// marched before it, so iso skips empty bricks and cells like the other
// models, with the same image. At longer steps a crossing is refined against
// the sample the ray carried (across bricks), and iso skips nothing.
constexpr double kIsoBackStep = 1.5;
bool iso_back_sample(const RenderSettings& s);

// Whether an empty-space cell may change a ray, whatever the ray holds so
// far: for emission and emission-absorption (whose zero-opacity samples
// change nothing) the classify pass's test on the CPU, in double and one
// table entry wider each side, so that a cell it calls empty the shader's
// float test calls empty too; for MIP / MinIP brick_may_contribute's rule per
// cell (clearly below / above the window, entry 0 / 255 transparent); for iso
// (where iso_back_sample holds) the iso channel clearly below the iso value;
// for average every sample windowing to 0 exactly (it adds nothing; the
// rays take their length from their chord). Marching only the box of the
// cells it keeps (BrickRenderer::march_box; an average whose table shows
// entry 0 marches whole bricks and walks past the empty cells) then gives
// the image of marching them all.
class CellOpacity {
 public:
  // `value_scales`: per drawn channel, data units per texel unit.
  CellOpacity(const RenderSettings& s, const TransferTable& table, const std::vector<double>& value_scales);
  // `texel_range`: one channel's (min, max) of a cell, atlas texel units (BrickPool cell ranges).
  bool may_contribute(uint32_t channel, glm::vec2 texel_range) const;
  uint32_t channels() const { return static_cast<uint32_t>(channels_.size()); }
  OpticalModel model() const { return model_; }
  // Average whose table shows entry 0 (average_shows_zero): march_box keeps the whole brick.
  bool marches_whole_bricks() const { return whole_bricks_; }
  // Channel `channel`'s texel value windowed as the rays window it (0..1, gamma applied).
  double windowed(uint32_t channel, double texel) const;
  // Equal for settings that classify every cell alike (what a cached box is keyed by); never 0.
  uint64_t hash() const { return hash_; }

 private:
  struct Channel {
    bool enabled = false;
    double lo = 0, hi = 1, gamma = 1, scale = 1;
    std::array<uint16_t, VXR_TF_SIZE> opaque_upto{};  // entries 0..i with non-zero opacity
  };
  OpticalModel model_ = OpticalModel::kEmissionAbsorption;
  bool whole_bricks_ = false;
  bool iso_skips_ = false;  // iso: iso_back_sample
  uint32_t iso_channel_ = 0;
  double iso_norm_ = 0;  // the iso value windowed, as the rays compare it
  std::vector<Channel> channels_;
  uint64_t hash_ = 0;
};

// Whether a ray's state fits the one RGBA32F texel the multipass waves carry
// between dispatches (brick_raycast.comp pack_ray): ea with one channel or
// composite, emission, mip/minip with one channel, average with up to 3, iso.
// The others march tiled (one dispatch, no state between passes).
bool brick_state_fits_texel(const RenderSettings& s, uint32_t channels);

// "visited 123 drawn 45 (fallback 2) empty 30 culled 12 missing 3 samples 1.2M uploaded 0.4 MiB hit 97%"
std::string format_stats(const BrickFrameStats& s);

// BrickRenderer::build_tile_lists' scratch for the rays of a view's 8x8
// tiles and their 4x2 blocks (TileFrusta in brick_renderer.cpp), kept
// between views so a frame allocates nothing once sizes settle.
struct TileRayScratch {
  std::vector<glm::dvec3> tiles, groups;  // two vectors a tile or block
  std::vector<uint8_t> groups_made;       // per tile, a bit per block whose rays are made
  std::vector<glm::dvec2> group_spans;    // each 4-pixel column's and 2-pixel row's NDC span
  // A kept block's box (relative to the eye, grown; its view depths) to test
  // against a tile's blocks (`groups`, bits) once the view's bricks are in.
  struct GroupTest {
    size_t tile;
    glm::dvec3 lo, hi;
    glm::dvec2 span;
    uint8_t groups;
  };
  std::vector<GroupTest> group_tests;
};

class BrickRenderer final : public VolumeRenderer {
 public:
  // Bricks whose eye is this many of their voxels away, or more (on any
  // axis), march without empty-space cells: float positions there are too
  // coarse for the cells' band (record_view).
  static constexpr double kCellEyeLimit = 8192.0;
  // A walked brick's kept cells go to the tile lists in blocks of this many
  // cells a side (march_box), each with the view depths it spans.
  static constexpr uint32_t kBlockCells = 4;

  static Result<std::unique_ptr<BrickRenderer>> create(gpu::Context& ctx, const ChunkSource& source,
                                                       const BrickRendererOptions& options = {});

  // VolumeRenderer. Per view: one slice of the frame's brick table, work
  // list and parameter ring, and one descriptor set (max_views per frame).
  Status begin_frame(VkCommandBuffer cmd, const BrickFrameSettings& frame) override;
  Status record_view(VkCommandBuffer cmd, const Camera& camera, const RenderSettings& settings,
                     const BrickFrameSettings& frame, const RenderTarget& target,
                     BrickFrameStats* stats = nullptr) override;
  VolumePlacement placement() const override;

  // One frame of one view recorded, submitted, waited for and read back
  // (tests, PNG output): premultiplied RGBA, top row first. Complete every
  // frame: missing bricks are drawn from their nearest resident ancestor;
  // without a stream cache they are read after the frame, within the budget.
  // `underlay`, if given, records what the volume is drawn over (e.g.
  // AnnotationRenderer::record) into the same command buffer, before the view.
  using UnderlayRecorder = std::function<Result<ViewUnderlay>(VkCommandBuffer)>;
  Result<ImageRgba8> render(const Camera& camera, const RenderSettings& settings, const BrickFrameSettings& frame,
                            uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr,
                            const UnderlayRecorder& underlay = {});
  // render() into `out`, whose pixels are reused when it has the size: frame
  // loops (stills, movies, benchmarks) then allocate no image per frame.
  Status render_into(ImageRgba8& out, const Camera& camera, const RenderSettings& settings,
                     const BrickFrameSettings& frame, uint32_t width, uint32_t height,
                     BrickFrameStats* stats = nullptr, const UnderlayRecorder& underlay = {});
  // The same frame before the rounding to 8 bits (numerics tests, error
  // measurements): premultiplied RGBA floats.
  Result<ImageRgbaF> render_float(const Camera& camera, const RenderSettings& settings,
                                  const BrickFrameSettings& frame, uint32_t width, uint32_t height,
                                  BrickFrameStats* stats = nullptr, const UnderlayRecorder& underlay = {});

  // Loads `level` of the source at `timepoint` into one 3D texture per drawn
  // channel (refused past the device's 3D image limit) for render_monolithic().
  Status set_monolithic(uint32_t level, uint32_t timepoint = 0);
  Result<ImageRgba8> render_monolithic(const Camera& camera, const RenderSettings& settings, const LodSettings& clip,
                                       uint32_t width, uint32_t height, BrickFrameStats* stats = nullptr);

  BrickPool& pool() { return *pool_; }
  uint32_t channels() const { return pool_->channels(); }
  // Bricks requested from the stream cache and not yet copied in.
  size_t pending_bricks() const { return pending_.size(); }

  // Makes the pool fit `settings` before frames draw with them: gradients
  // (gradient opacity, iso normals) need an apron of 2 in the atlas, so the
  // first settings that need it rebuild the pool with one (vkDeviceWaitIdle,
  // bricks loaded again). Call it outside any command buffer's recording of
  // this renderer's work: before begin_frame, or never (record_view then asks
  // for the rebuild and the next begin_frame does it; until then gradients
  // read the narrower apron). render() calls it.
  Status prepare(const RenderSettings& settings);

 private:
  BrickRenderer(gpu::Context& ctx, const ChunkSource& src) : ctx_(ctx), src_(src) {}
  Status ensure_target(uint32_t width, uint32_t height);
  // One frame of one view into `target`, submitted and waited for (render, render_float).
  Status draw_and_wait(const Camera& camera, const RenderSettings& settings, const BrickFrameSettings& frame,
                       RenderTarget target, BrickFrameStats* stats, const UnderlayRecorder& underlay);
  // The accumulation image holds at least width x height (rays' state between
  // passes, and final float pixels on their way to a blit).
  Status ensure_accum(uint32_t width, uint32_t height);
  // Records the transfer table's upload when it changed (once per frame at most).
  Status record_transfer(VkCommandBuffer cmd, const TransferTable& table);
  // The classify pass's outputs sized for the pool and table: cell keys
  // (brick_raycast.comp binding 11) and emptiness bits (13, and 14 over its
  // start); written into every descriptor set.
  Status ensure_cell_keys();
  // A uniform window of `declared` bytes over `buffer` from `offset`: as much
  // of it as the device's uniform range and the buffer's end allow.
  uint64_t window_bytes(uint64_t declared, const gpu::Buffer& buffer, uint64_t offset) const;
  // The uniform window over the cell bits from `offset` (a view's region): 64 KiB or what the device allows.
  uint64_t cell_bits_window_bytes(uint64_t offset) const;
  uint64_t cell_bits_align() const;  // of a view's region: both its descriptors' offset alignments
  // Rebuilds the pool with `apron` (waits for the device; rebinds every set).
  Status rebuild_pool(uint32_t apron);
  // The frame's timepoint: its top level pinned (begin_frame, before any copy is recorded).
  Status ensure_timepoint(uint32_t timepoint);
  // Pins the top level of `timepoint` and, with preload_if_fits, every chunk.
  Status pin_resident(uint32_t timepoint);
  // The atlases a set binds, per drawn channel (binding 0), and their texel
  // views (binding 17) where the rays filter by hand; no views: they sample.
  struct Atlases {
    std::vector<const gpu::Image*> images;
    std::vector<const gpu::ImageTexels*> texels;
  };
  void bind_atlases(VkDescriptorSet set, const Atlases& atlases);
  Atlases pool_atlases() const;
  Atlases mono_atlases() const;  // set_monolithic's
  // What the rays need to read them (record_cast).
  struct AtlasReads {
    glm::uvec3 texels{0};      // the atlas's size in texels (an atlas of texel words is wider)
    uint32_t texel_bytes = 0;  // hand filtering (constant 115): 1 (u8 quads) or 2 (u16 pairs); 0: the sampler
    glm::uvec2 pitch{0};       // row and slice pitch in view elements (hand filtering)
  };
  // Of atlas `a` (channel 0's; the others share its layout), read by hand through texel views or sampled.
  static AtlasReads reads_of(const gpu::Image& a, bool by_hand);
  // Which per-ray reads go through a texel view or uniform buffer over their
  // storage buffer (brick_raycast.comp constants 108, 109, 111), faster on
  // lavapipe: where what the view reads fits. lavapipe runs both sides of a
  // branch, so each is a constant.
  struct FastReads {
    bool record_texels = false;  // the brick records and work items as texels (15 over 4, 18 over 6)
    bool cell_bits = false;  // the E-A and emission cells' emptiness bits (14 over 13)
    bool key_texels = false;  // the MIP / MinIP cells' keys as texels (16 over 11; constant 111)
  };
  // One pipeline's specialisation constants: raycast_core.glsl ids 100..105
  // and 112, brick_raycast.comp 106..111 and 113..115.
  struct ShaderVariant {
    uint32_t model = VXR_MODEL_EMISSION_ABSORPTION;  // VXR_MODEL_*
    uint32_t channels = 1;
    bool gradient = false, depth_color = false, gamma = false, naive_opacity = false;
    bool composite = false;  // channels blend into one medium (VXR_BLEND_COMPOSITE)
    bool cells = false;      // its dispatches may walk empty-space cells
    FastReads fast;
    SampleWork work = SampleWork::kShade;
    bool no_bricks = false;  // no brick loop: for tiles no brick touches
    bool waves = false;      // its dispatches carry rays between passes (BrickPassMode::kMultipass)
    bool classify = false;   // the cell classification pass's pipeline (no other dispatch carries its code)
    uint32_t texel_bytes = 0;  // AtlasReads::texel_bytes
    bool hue_tables = false;   // lookups through the single-hue rows (TransferTable::hue)
  };
  // The pipeline specialised for the settings (model: VXR_MODEL_*, channels,
  // features), for whether its dispatches use empty-space cells, the
  // fast reads it uses (FastReads) and whether it marches multipass waves.
  Result<const gpu::ComputePipeline*> pipeline_for(const RenderSettings& s, uint32_t model, uint32_t texel_bytes,
                                                   bool cells, FastReads fast, SampleWork work, bool waves,
                                                   bool no_bricks = false);
  // Whether rays of `model` (VXR_MODEL_*) look colours up in the single-hue
  // rows (BrickRendererOptions::hue_tables, the uploaded table's hues).
  bool hue_lookups(uint32_t model) const;
  // The classification pass's pipeline: only what classify_cells reads is specialised.
  Result<const gpu::ComputePipeline*> classify_pipeline(const RenderSettings& s, uint32_t model);
  // The pipeline for these constants, built on first use.
  Result<const gpu::ComputePipeline*> variant(const ShaderVariant& v);
  // The part of brick `key` its rays march, in its local voxels: the brick
  // clipped to the ROI and, with `cells` (cell skipping on), to the box of
  // its cells that `cells` says may change a ray. Empty
  // (lo >= hi on an axis) when no cell may.
  // With `cells`, `facts` (if given) says what a walk through them would meet.
  static constexpr uint32_t kMinIpBins = 32;
  struct CellFacts {
    // Empty cells in 2x2x2 groups that keep some cell: what walking cells instead of groups could skip.
    uint32_t split = 0;
    uint32_t boxed_groups = 0;  // groups meeting the box of kept cells (what a walk may cross)
    bool all_kept = false;      // every cell in the box is kept: a walk would find no empty cell
    bool every_kept = false;    // every cell of the brick is kept (an average over whole bricks walks otherwise)
    bool none_kept = false;     // no cell is kept (an average over whole bricks: its rays take no sample)
    // One-channel MinIP (see record_view): the lowest windowed maximum of
    // any cell, and the cells by windowed minimum in kMinIpBins bins over 0..1.
    float lowest_max = 1.0f;
    std::array<uint32_t, kMinIpBins> minima{};
  };
  // The brick's box in its local voxels, clipped to the ROI and, with
  // `cells`, to the box of its kept cells (not for average: see the body).
  // `blocks` (with `cells`; else null): the kept cells' boxes in blocks of
  // kBlockCells^3 cells, each the tight box of the block's kept cells
  // grown like the march box (local voxels, not clipped to the ROI), cached
  // per slot and valid until the next call.
  BrickBox march_box(const ChunkKey& key, const LodSettings& clip, const CellOpacity* cells,
                     CellFacts* facts = nullptr, const std::vector<BrickBox>** blocks = nullptr);
  // Fills the brick record for `key` (`atlas_origin`: interior origin in
  // texels; `box`: march_box, local voxels; `walk`: its rays walk cells;
  // `no_samples`: its rays take no sample (an average over whole bricks lists it so they are cast)).
  void fill_record(void* record, const ChunkKey& key, const glm::vec3& atlas_origin, const LodView& view,
                   const LodSettings& clip, const BrickBox& box, bool walk, bool no_samples = false) const;
  // Records one view's dispatches with `set` and writes the result into `target`.
  // Which empty-space cells the rays walk: none, the pool's (BrickCells), or
  // groups of 2x2x2 of them where the pool's are smaller than 4 voxels
  // (MIP / MinIP always walk those; E-A and emission as record_view decides).
  enum class CellWalk { kOff, kCells, kGroups };
  // What a view's classify pass wrote and from what: cell bits (E-A,
  // emission: per brick record, in the view's region of the bits buffer) or
  // keys (MIP / MinIP: per slot, shared by the views). The buffers keep each
  // view's last results, so a view whose inputs equal them (a still camera
  // or head, an idle `vxr view`, a benchmark's repeated frames) skips the pass.
  struct CellClassInputs {
    std::vector<std::pair<ChunkKey, uint32_t>> records;  // per brick record: its key and slot (the ranges read)
    std::array<glm::vec4, VXR_MAX_CHANNELS> window{};   // RaycastParams::window
    std::vector<glm::vec4> table;                         // the transfer table
    glm::vec2 iso{0.0f};                                  // iso: RaycastParams::iso.x and the iso channel
    uint32_t model = 0, walked_cells = 0, range_cells = 0;
    uint64_t bits_offset = 0, bits_bytes = 0;  // the view's region of cell_bits_
    bool operator==(const CellClassInputs&) const = default;
    bool writes_keys() const { return model == VXR_MODEL_MIP || model == VXR_MODEL_MINIP; }
    // Keys written under these settings equal those of `o` for any slot both read.
    bool same_keys(const CellClassInputs& o) const {
      return window == o.window && table == o.table && iso == o.iso && model == o.model &&
             walked_cells == o.walked_cells && range_cells == o.range_cells;
    }
  };
  // Forgets what this view's pass overwrites for the other views: their bits
  // where the regions meet, or their keys where the settings differ.
  void forget_overwritten(uint32_t view, const CellClassInputs& written);
  // Where a view's work items are in its work list, as (first entry, count):
  // the multipass waves, or a tiled frame's tiles (entries: tile index, x, y
  // in pixels) that some brick walking its cells touches, those whose bricks
  // all march without a walk (plain), and those no brick touches, in that order.
  struct WorkSpans {
    std::vector<glm::uvec2> waves;
    glm::uvec2 marched_tiles{0, 0}, plain_tiles{0, 0}, empty_tiles{0, 0};
    // build_tile_lists' by_groups: the marched tiles' 4x2 blocks some entry
    // reaches (x: first entry, y: entries padded to whole workgroups of 8), and how many.
    bool by_groups = false;
    glm::uvec2 marched_groups{0, 0};
    uint32_t groups_reached = 0;
    uint32_t tile_entries = 0, blocks = 0;  // build_tile_lists: bricks on tiles, blocks projected
    uint32_t list_texel = 0;  // the list's first entry as a texel of binding 18 (the whole work-list buffer)
  };
  // `model`: the packed parameters' VXR_MODEL_* (control.x). `records`:
  // where the view's brick records start in table_ (bytes, a multiple of
  // 16). `classify`: the view's records, window, table and bits region (null:
  // no cells walked); when they are new, they are swapped into the view's
  // entry of classified_.
  Status record_cast(VkCommandBuffer cmd, VkDescriptorSet set, const RenderSettings& s, uint32_t model, uint32_t width,
                     uint32_t height, uint32_t bricks, uint64_t records, const AtlasReads& atlas, BrickPassMode mode,
                     const WorkSpans& spans, const RenderTarget& target, CellWalk cells,
                     SampleWork work, CellClassInputs* classify, BrickFrameStats* stats);
  // Multipass work items (brick, 8x8 tile) grouped into waves, written at
  // `dst` (capacity entries); returns (first item, count) per wave.
  // `ax`, `ay`: the ray grid (identity_warp, or the lens warp's).
  // `boxes`: per drawn brick, the world box its rays march (empty: none).
  Result<std::vector<glm::uvec2>> build_waves(const std::vector<BrickBox>& boxes, const LodView& view,
                                              const WarpAxis& ax, const WarpAxis& ay, glm::uvec4* dst, size_t capacity, size_t* used);
  // Whether a tiled view's image is its own (or the accumulation image's)
  // and has no underlay, so one clear can write its empty rays' pixels.
  bool clears_tiled_view(const RenderTarget& target, uint32_t w, uint32_t h) const;
  // One-channel MinIP: whether walking the view's cells can pay (facts summed over its walked bricks).
  static bool minip_walk_pays(const CellFacts& f);
  // Whether this view's iso crossings read their sample back in their brick
  // (iso_back_sample, with the slots' apron of 2), so iso skips empty space.
  bool iso_skips(const RenderSettings& s) const;
  // The view's clip for iso_crossing and the average's length: the iso
  // flag, the region (volume within the ROI) and the cut plane.
  void set_clip(shader::RaycastParams& params, const RenderSettings& s, const LodSettings& clip) const;
  // Tiled: per 8x8 tile, the front-to-back list of bricks whose screen
  // rectangle touches it; then the tiles with a brick that walks (`walks`,
  // per drawn brick), those with bricks that do not, and those without
  // any (their spans go into `spans`).
  // `blocks`: per drawn brick, [first, end) of `block_boxes` (world boxes
  // of its kept cells, march_box): a tile gets the brick only where its
  // rays can meet one of them, with the view depths where they can
  // (TileFrusta; its rays march only those); an empty span, a brick within
  // one tile and bricks past max_tile_blocks clip nothing.
  // `by_groups`: the tiles with a brick that walks also as the 4x2 blocks
  // (spans->marched_groups) whose rays can meet a brick's screen rectangle
  // or, where it has them, one of its blocks (TileFrusta::group_meets).
  // `keep_rays` (an average over whole bricks, average_shows_zero): a tile
  // whose rays meet none of a brick's blocks keeps it, with depths that
  // clip every sample, so its rays are still cast (and show entry 0).
  Status build_tile_lists(const std::vector<BrickBox>& boxes, const std::vector<uint8_t>& walks,
                          const std::vector<glm::uvec2>& blocks, const std::vector<BrickBox>& block_boxes,
                          const LodView& view, const WarpAxis& ax, const WarpAxis& ay, bool by_groups,
                          bool keep_rays, glm::uvec4* dst, size_t capacity, size_t* used, WorkSpans* spans);
  // A work list of at least `entries` (twice the old at least), the old one
  // kept until the next begin_frame: the frame's earlier views still read it.
  Status grow_work_list(size_t entries);
  // item_texels_ for the current items_.
  Status make_item_texels();
  static constexpr VkBufferUsageFlags kWorkListUsage =
      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT;
  LodView view_for(const Camera& camera, uint32_t width, uint32_t height) const;

  gpu::Context& ctx_;
  const ChunkSource& src_;
  BrickRendererOptions opt_;
  std::unique_ptr<BrickPool> pool_;
  std::shared_ptr<BrickPipelines> pipes_;
  const gpu::ComputePipeline* pipeline_ = nullptr;  // emission-absorption, one channel; its set layout is the sets'
  gpu::Handle<VkDescriptorPool> desc_pool_;
  VkDescriptorSet mono_set_ = VK_NULL_HANDLE;
  std::vector<VkDescriptorSet> view_sets_;  // one per view of a frame
  gpu::Handle<VkSampler> linear_;
  gpu::Handle<VkBufferView> transfer_rows_;  // transfer_buf_'s colour and opacity rows as RGBA32F texels
  gpu::Image target_, float_target_, accum_;
  gpu::ImageReadback readback_;  // render()'s and render_float()'s staging, kept between frames
  gpu::Image no_under_depth_, no_under_color_;  // 1x1, bound where a view has no underlay
  std::vector<gpu::Image> mono_tex_;  // per drawn channel
  std::vector<gpu::ImageTexels> mono_texels_;  // per drawn channel, or none (declared after mono_tex_: destroyed first)
  gpu::Buffer no_texels_buf_;  // 16 bytes: the stand-in texel view of sets whose rays sample
  gpu::Handle<VkBufferView> no_texels_;
  std::vector<uint32_t> tile_rows_;  // build_tile_lists: the tile rows in dispatch order, kept while the height stays
  std::vector<uint8_t> tile_kinds_;  // build_tile_lists' scratch: each tile's kind (WorkSpans)
  struct TileEntry {
    uint32_t brick;
    glm::vec2 depth;  // view depths its rays march there
  };
  std::vector<std::vector<TileEntry>> tile_entries_;  // build_tile_lists' scratch: per tile, kept between views
  std::vector<glm::dvec2> tile_depths_;               // build_tile_lists' scratch: a brick's depths per tile
  std::vector<uint8_t> tile_groups_;                  // build_tile_lists' scratch: per tile, the 4x2 blocks reached
  TileRayScratch tile_rays_;                          // build_tile_lists' scratch: the tiles' rays (TileFrusta)
  std::vector<BrickBox> march_world_;  // record_view's scratch: per drawn brick, the world box its rays march
  std::vector<uint8_t> walks_;         // record_view's scratch: per drawn brick, whether it walks its cells
  std::vector<glm::uvec2> blocks_;     // record_view's scratch: per drawn brick, its span of block_world_
  std::vector<BrickBox> block_world_;  // record_view's scratch: the walked bricks' blocks (march_box), world boxes
  std::vector<gpu::Image> retired_;  // replaced while a frame may still use them; freed at begin_frame
  std::vector<gpu::Buffer> retired_buffers_;  // likewise (a work list that grew)
  std::vector<gpu::Handle<VkBufferView>> retired_views_;  // likewise (its texel view)
  gpu::Buffer table_, counters_, items_, params_, transfer_buf_, tf_staging_, cell_keys_, cell_bits_;
  // table_ as RGBA32F texels for the rays' record reads (declared after it: destroyed first).
  gpu::Handle<VkBufferView> table_texels_;
  bool table_texels_fit_ = false;  // table_texels_ covers the whole table
  gpu::Handle<VkBufferView> item_texels_;  // items_ as RGBA32UI texels (binding 18)
  bool item_texels_fit_ = false;           // item_texels_ covers the whole list
  // cell_keys_ as R32F texels, which the rays' MIP / MinIP key tests read (declared after it: destroyed first).
  gpu::Handle<VkBufferView> cell_key_texels_;
  std::vector<std::optional<CellClassInputs>> classified_;  // per view of a frame: what its pass left (none: unknown)
  CellClassInputs classify_scratch_;  // record_view fills it each view; swapped with classified_'s entry when new
  gpu::Handle<VkQueryPool> timestamps_;  // render(): two per frame; null without timestamps
  VkDeviceSize params_stride_ = 0;
  // This frame: views recorded, and the table / work-list entries they took.
  uint32_t views_ = 0;
  size_t table_used_ = 0, items_used_ = 0, bits_used_ = 0;
  bool tf_recorded_ = false;
  std::vector<glm::vec4> tf_uploaded_;
  std::array<std::optional<glm::vec3>, VXR_MAX_CHANNELS> tf_hues_;  // tf_uploaded_'s (TransferTable::hue)
  std::vector<ChunkKey> pending_;    // streaming: requested, not yet copied in
  std::vector<ChunkKey> requests_;   // render(): the frame's requests, read after it
  uint64_t frame_number_ = 0;
  UploadStats last_upload_;          // streaming: what this frame's begin_frame copied in
  uint32_t mono_level_ = UINT32_MAX, mono_timepoint_ = 0;
  uint32_t pinned_timepoint_ = 0;
  uint32_t apron_wanted_ = 0;        // a view needed a wider apron: the next begin_frame rebuilds the pool
  std::vector<glm::dvec3> ray_dirs_;  // per pixel 1/direction, for build_waves
  std::tuple<glm::dvec3, glm::dvec3, glm::dvec3> rays_for_;
  glm::uvec4 rays_grid_{0};  // ray_dirs_'s grid: full sizes and warp bands
  std::vector<uint32_t> pixel_wave_;
  // Per atlas slot: cells [lo, hi) (cell indices) of the brick `key` that may
  // change a ray under the settings CellOpacity::hash() gave `settings`.
  struct OccupiedCells {
    ChunkKey key;
    uint64_t settings = 0;  // 0: not computed
    glm::uvec3 lo{0}, hi{0};
    CellFacts facts;
    std::vector<BrickBox> blocks;  // march_box's blocks, local voxels, grown by the band
  };
  std::vector<OccupiedCells> occupied_;
  std::vector<uint8_t> kept_scratch_;  // march_box: which cells a brick keeps
  std::vector<double> value_scales_;  // per drawn channel: data units per texel unit
};

}  // namespace vxr

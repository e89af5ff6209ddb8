// The frame path: VolumeRenderer records into a caller's command buffer and
// image. Why the pictures are right: every target kind is compared with
// render()'s RGBA8 image (the golden-tested path) byte for byte, or with the
// sRGB encoding of the same linear values; two views in one command buffer
// equal two separate frames; streamed bricks converge to the same image.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "gpu/pipeline_cache.h"
#include "gpu/resources.h"
#include "gpu_fixture.h"
#include "render/lod/brick_renderer.h"
#include "volume/chunk_cache.h"
#include "volume/dense_chunk_source.h"
#include "volume/procedural_source.h"

using namespace vxr;

namespace {

std::shared_ptr<ProceduralSource> vessels_source(uint64_t side) {
  ProceduralOptions o;
  o.dims = {side, side, side};
  o.noise_max = 6;
  auto r = ProceduralSource::create(o);
  REQUIRE(r.is_ok());
  return std::shared_ptr<ProceduralSource>(std::move(r).value());
}

RenderSettings vessels() {
  RenderSettings s;
  s.channels[0].colormap = "hot";
  s.channels[0].window_lo = 8;
  s.channels[0].window_hi = 200;
  s.step_voxels = 0.5;
  s.density = 0.3;
  return s;
}

// An 8^3-slot pool streaming from `cache` (none: loads in the frame); `o`: whatever else a test changes.
std::unique_ptr<BrickRenderer> make_renderer(const ChunkSource& src, ChunkCache* cache = nullptr,
                                             BrickRendererOptions o = {}) {
  o.pool.slots = {8, 8, 8};
  o.stream_from = cache;
  auto r = BrickRenderer::create(test::gpu_context(), src, o);
  REQUIRE(r.is_ok());
  return std::move(r).value();
}

// render() until nothing is missing (the reference every target is compared with).
ImageRgba8 converged(BrickRenderer& r, const Camera& cam, const RenderSettings& s, uint32_t w, uint32_t h) {
  for (int i = 0; i < 64; ++i) {
    BrickFrameStats st;
    auto img = r.render(cam, s, {}, w, h, &st);
    REQUIRE(img.is_ok());
    if (st.lod.missing == 0) return *img;
  }
  FAIL("did not converge");
  return {};
}

struct Target {
  gpu::Image image;
  RenderTarget rt() const {
    return {image.image, image.view ? image.view.get() : VK_NULL_HANDLE, image.format,
            {image.extent.width, image.extent.height}, VK_IMAGE_LAYOUT_GENERAL};
  }
};

Target make_target(VkFormat format, uint32_t w, uint32_t h, bool storage) {
  VkImageUsageFlags usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  usage |= storage ? VK_IMAGE_USAGE_STORAGE_BIT : VK_IMAGE_USAGE_SAMPLED_BIT;  // every image gets a view
  auto img = gpu::create_image(test::gpu_context(), {VK_IMAGE_TYPE_2D, format, {w, h, 1}, usage, "test target"});
  REQUIRE(img.is_ok());
  Target t{std::move(img).value()};
  REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
    gpu::transition_image(cmd, t.image, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                          VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT);
  }).is_ok());
  if (!storage) t.image.view.reset();
  return t;
}

// A 2w x h storage image and its left and right halves as view targets.
Target side_by_side(uint32_t w, uint32_t h, RenderTarget* left, RenderTarget* right) {
  Target t = make_target(VK_FORMAT_R8G8B8A8_UNORM, 2 * w, h, true);
  *left = *right = t.rt();
  left->rect = {{0, 0}, {w, h}};
  right->rect = {{int32_t(w), 0}, {w, h}};
  return t;
}

// Records one frame of `views` (camera, target rect) into one command buffer.
void record_frame(BrickRenderer& r, const RenderSettings& s, const std::vector<std::pair<Camera, RenderTarget>>& views) {
  Status recorded = Status::ok();
  REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
    recorded = r.begin_frame(cmd, {});
    for (const auto& [cam, rt] : views)
      if (recorded) recorded = r.record_view(cmd, cam, s, {}, rt);
  }).is_ok());
  REQUIRE_MESSAGE(recorded.is_ok(), recorded.to_string());
}

std::vector<uint8_t> read_back(gpu::Image& img) {
  std::vector<uint8_t> out(size_t(img.extent.width) * img.extent.height * gpu::format_texel_bytes(img.format));
  img.layout = VK_IMAGE_LAYOUT_GENERAL;
  REQUIRE(gpu::readback_image(test::gpu_context(), img, out.data(), out.size()).is_ok());
  return out;
}

// RGBA8 bytes of `px` (a and b side by side, as wide as both) that differ from them.
int bytes_off_side_by_side(const std::vector<uint8_t>& px, const ImageRgba8& a, const ImageRgba8& b) {
  const uint32_t w = a.width + b.width;
  int diff = 0;
  for (uint32_t y = 0; y < a.height; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) {
        const uint8_t want = x < a.width ? a.at(x, y)[c] : b.at(x - a.width, y)[c];
        diff += px[(size_t(y) * w + x) * 4 + c] != want;
      }
  return diff;
}

}  // namespace

TEST_CASE("volume renderer: a caller's RGBA8 storage image, a BGRA8 image (blit) and render() hold the same bytes") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto r = make_renderer(*src);
  const Camera cam = orbit_camera(r->placement(), 30, 20);
  const ImageRgba8 ref = converged(*r, cam, vessels(), 64, 48);

  Target rgba = make_target(VK_FORMAT_R8G8B8A8_UNORM, 64, 48, true);
  Target bgra = make_target(VK_FORMAT_B8G8R8A8_UNORM, 64, 48, false);
  record_frame(*r, vessels(), {{cam, rgba.rt()}});
  record_frame(*r, vessels(), {{cam, bgra.rt()}});
  const std::vector<uint8_t> a = read_back(rgba.image), b = read_back(bgra.image);
  CHECK(std::memcmp(a.data(), ref.pixels.data(), a.size()) == 0);
  int max_abs = 0;
  for (size_t i = 0; i < b.size(); i += 4)
    for (int c = 0; c < 4; ++c) {
      const int swapped = c == 3 ? c : 2 - c;
      max_abs = std::max(max_abs, std::abs(int(b[i + c]) - int(ref.pixels[i + swapped])));
    }
  CHECK(max_abs == 0);
}

TEST_CASE("volume renderer: an sRGB target holds the sRGB encoding of the linear values a float target gets") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto r = make_renderer(*src);
  const Camera cam = orbit_camera(r->placement(), -40, 10);
  (void)converged(*r, cam, vessels(), 64, 64);
  Target lin = make_target(VK_FORMAT_R32G32B32A32_SFLOAT, 64, 64, false);
  Target srgb = make_target(VK_FORMAT_R8G8B8A8_SRGB, 64, 64, false);
  record_frame(*r, vessels(), {{cam, lin.rt()}});
  record_frame(*r, vessels(), {{cam, srgb.rt()}});
  const std::vector<uint8_t> fb = read_back(lin.image), sb = read_back(srgb.image);
  std::vector<float> f(fb.size() / 4);
  std::memcpy(f.data(), fb.data(), fb.size());
  int max_abs = 0, lit = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const double v = std::clamp(double(f[i]), 0.0, 1.0);
    const double e = i % 4 == 3 ? v : v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    max_abs = std::max(max_abs, std::abs(int(std::lround(e * 255.0)) - int(sb[i])));
    lit += (i % 4 == 0 && sb[i] > 0) ? 1 : 0;
  }
  CHECK(lit > 40);  // the vessels are in view
  CHECK(max_abs <= 1);  // the format's encoder rounds; Vulkan allows it to be off by one
}

TEST_CASE("volume renderer: two views into halves of one image in one command buffer equal two frames") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto r = make_renderer(*src);
  const Camera left = orbit_camera(r->placement(), 10, 0), right = orbit_camera(r->placement(), 80, 30);
  const ImageRgba8 a = converged(*r, left, vessels(), 32, 32), b = converged(*r, right, vessels(), 32, 32);
  RenderTarget l, rr;
  Target both = side_by_side(32, 32, &l, &rr);
  record_frame(*r, vessels(), {{left, l}, {right, rr}});
  CHECK(bytes_off_side_by_side(read_back(both.image), a, b) == 0);
}

TEST_CASE("volume renderer: each view of a frame keeps its own cell classification, and one view's pass never stales another's") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto r = make_renderer(*src);
  const Camera left = orbit_camera(r->placement(), 10, 0), right = orbit_camera(r->placement(), 80, 30);
  RenderTarget l, rr;
  Target both = side_by_side(32, 32, &l, &rr);
  // Per view: E-A (bits in the view's region) with two windows, then MIP
  // (keys per slot, shared by the views) with two windows, so each view's
  // pass rewrites keys the other one read.
  RenderSettings ea_near = vessels(), ea_far = vessels(), mip_low = vessels(), mip_high = vessels();
  ea_far.channels[0].window_lo = 60;
  mip_low.model = mip_high.model = OpticalModel::kMip;
  mip_high.channels[0].window_lo = 60;
  const struct {
    const char* what;
    RenderSettings left, right;
    uint32_t repeat_classify;  // per view, classify passes in the frames after the first
  } cases[] = {{"e-a, one window", ea_near, ea_near, 0}, {"e-a, two windows", ea_near, ea_far, 0},
               {"mip, two windows", mip_low, mip_high, 1}, {"mip, one window", mip_low, mip_low, 0}};
  for (const auto& c : cases) {
    INFO(std::string(c.what));
    const ImageRgba8 a = converged(*r, left, c.left, 32, 32), b = converged(*r, right, c.right, 32, 32);
    for (int frame = 0; frame < 3; ++frame) {
      BrickFrameStats sl, sr;
      Status recorded = Status::ok();
      REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
        recorded = r->begin_frame(cmd, {});
        if (recorded) recorded = r->record_view(cmd, left, c.left, {}, l, &sl);
        if (recorded) recorded = r->record_view(cmd, right, c.right, {}, rr, &sr);
      }).is_ok());
      REQUIRE(recorded.is_ok());
      if (frame > 0) {
        CHECK(sl.classify_passes == c.repeat_classify);
        CHECK(sr.classify_passes == c.repeat_classify);
      }
      CHECK(bytes_off_side_by_side(read_back(both.image), a, b) == 0);
    }
  }
}

TEST_CASE("volume renderer: views that need a longer work list than it was made with grow it, mid-frame too, and keep the image") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto roomy = make_renderer(*src);
  BrickRendererOptions o;
  o.max_work_items = 40;  // a 32x32 view alone needs more (16 tiles, twice, and their brick lists)
  auto made = make_renderer(*src, nullptr, o);
  BrickRenderer& tight = *made;
  const Camera left = orbit_camera(roomy->placement(), 10, 0), right = orbit_camera(roomy->placement(), 80, 30);
  const ImageRgba8 a = converged(*roomy, left, vessels(), 32, 32), b = converged(*roomy, right, vessels(), 32, 32);
  RenderTarget l, rr;
  Target both = side_by_side(32, 32, &l, &rr);
  for (BrickPassMode mode : {BrickPassMode::kTiled, BrickPassMode::kMultipass}) {
    CAPTURE(int(mode));
    BrickFrameSettings f;
    f.mode = mode;
    for (int frame = 0; frame < 3; ++frame) {  // the first frames grow the list between the views
      Status recorded = Status::ok();
      REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
        recorded = tight.begin_frame(cmd, f);
        if (recorded) recorded = tight.record_view(cmd, left, vessels(), f, l);
        if (recorded) recorded = tight.record_view(cmd, right, vessels(), f, rr);
      }).is_ok());
      REQUIRE_MESSAGE(recorded.is_ok(), recorded.to_string());
      if (frame == 0) continue;  // bricks still arriving
      CHECK(bytes_off_side_by_side(read_back(both.image), a, b) == 0);
    }
  }
}

TEST_CASE("volume renderer: new poses and sizes build no pipeline and read nothing back") {
  test::GpuTestScope scope;
  auto src = vessels_source(128);
  auto r = make_renderer(*src);
  Target t = make_target(VK_FORMAT_R8G8B8A8_UNORM, 48, 48, true);
  record_frame(*r, vessels(), {{orbit_camera(r->placement(), 0, 0), t.rt()}});  // first frame: pipelines
  const uint64_t built = test::gpu_context().pipelines_built(), readbacks = gpu::readback_count();
  for (int i = 1; i <= 12; ++i) {
    RenderTarget part = t.rt();
    part.rect = {{i % 3, i % 5}, {uint32_t(40 - i), uint32_t(30 + i % 7)}};
    record_frame(*r, vessels(), {{orbit_camera(r->placement(), 29.0 * i, 7.0 * i - 40, 1.2 + 0.1 * i), part}});
  }
  CHECK(test::gpu_context().pipelines_built() == built);
  CHECK(gpu::readback_count() == readbacks);
}

TEST_CASE("volume renderer: streamed bricks arrive from the loader threads and converge to render()'s image") {
  test::GpuTestScope scope;
  auto src = vessels_source(256);
  const Camera cam = orbit_camera(VolumePlacement{{256, 256, 256}, {1, 1, 1}}, 20, 25, 1.3);
  auto plain = make_renderer(*src);
  const ImageRgba8 ref = converged(*plain, cam, vessels(), 64, 64);

  ChunkCache cache(src, {uint64_t(256) << 20, 2});
  auto r = make_renderer(*src, &cache);
  Target t = make_target(VK_FORMAT_R8G8B8A8_UNORM, 64, 64, true);
  uint64_t first_missing = 0, missing = 1;
  int frames = 0;
  for (; frames < 400 && missing > 0; ++frames) {
    BrickFrameStats st;
    Status recorded = Status::ok();
    REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
      recorded = r->begin_frame(cmd, {});
      if (recorded) recorded = r->record_view(cmd, cam, vessels(), {}, t.rt(), &st);
    }).is_ok());
    REQUIRE(recorded.is_ok());
    if (frames == 0) first_missing = st.lod.missing;
    missing = st.lod.missing;
    if (missing > 0) cache.wait_idle();  // let the loaders catch up; a frame itself never waits
  }
  MESSAGE("streamed: " << first_missing << " bricks missing at frame 0, complete after " << frames << " frames");
  CHECK(first_missing > 0);  // frame 0 drew ancestors while the loaders worked
  CHECK(missing == 0);
  const std::vector<uint8_t> px = read_back(t.image);
  int max_abs = 0;  // same bricks in other atlas slots: texel coordinates may round differently
  for (size_t i = 0; i < px.size(); ++i) max_abs = std::max(max_abs, std::abs(int(px[i]) - int(ref.pixels[i])));
  CHECK(max_abs <= 1);
}

TEST_CASE("volume renderer: streaming gradient opacity widens the apron at begin_frame and loads neighbours") {
  // The procedural source stores an apron of 1; gradients need 2. No prepare():
  // the first view asks, the next begin_frame rebuilds the pool (outside any
  // recording of its work), and streamed slots are filled from neighbouring
  // chunks the loader threads decoded (BrickPool::slot_chunks).
  test::GpuTestScope scope;
  auto src = vessels_source(256);
  REQUIRE(src->apron() == 1);
  const Camera cam = orbit_camera(VolumePlacement{{256, 256, 256}, {1, 1, 1}}, 20, 25, 1.3);
  RenderSettings s = vessels();
  s.gradient_opacity.enabled = true;
  s.gradient_opacity.hi = 0.05;
  auto plain = make_renderer(*src);
  const ImageRgba8 ref = converged(*plain, cam, s, 64, 64);  // render() prepares: apron 2 from its first frame
  CHECK(plain->pool().apron() == 2);

  ChunkCache cache(src, {uint64_t(256) << 20, 2});
  auto r = make_renderer(*src, &cache);
  CHECK(r->pool().apron() == 1);
  Target t = make_target(VK_FORMAT_R8G8B8A8_UNORM, 64, 64, true);
  uint64_t missing = 1;
  int frames = 0;
  for (; frames < 400 && (missing > 0 || frames < 2); ++frames) {
    BrickFrameStats st;
    Status recorded = Status::ok();
    REQUIRE(test::gpu_context().submit_and_wait([&](VkCommandBuffer cmd) {
      recorded = r->begin_frame(cmd, {});
      if (recorded) recorded = r->record_view(cmd, cam, s, {}, t.rt(), &st);
    }).is_ok());
    REQUIRE(recorded.is_ok());
    if (frames == 0) CHECK(r->pool().apron() == 1);  // drawn with what it had; rebuilt at the next begin_frame
    missing = st.lod.missing;
    if (missing > 0) cache.wait_idle();
  }
  MESSAGE("streamed with gradients: complete after " << frames << " frames");
  CHECK(r->pool().apron() == 2);
  CHECK(missing == 0);
  const std::vector<uint8_t> px = read_back(t.image);
  int max_abs = 0;  // same bricks in other atlas slots: texel coordinates may round differently
  for (size_t i = 0; i < px.size(); ++i) max_abs = std::max(max_abs, std::abs(int(px[i]) - int(ref.pixels[i])));
  CHECK(max_abs <= 1);
}

TEST_CASE("dense chunk source: a pyramid down to one chunk, aprons repeat edge voxels, stats bound payloads") {
  DenseVolume v;
  v.dims = {70, 33, 5};
  v.data.resize(v.byte_size());
  for (size_t i = 0; i < v.data.size(); ++i) v.data[i] = uint8_t((i * 7) % 251);
  auto s = DenseChunkSource::create({v}, 32, 2);
  REQUIRE(s.is_ok());
  const auto& levels = (*s)->levels();
  REQUIRE(levels.size() == 3);  // 70 -> 35 -> 18 along x
  CHECK(levels[0].chunk_counts == std::array<uint32_t, 3>{3, 2, 1});
  CHECK(levels.back().chunk_counts == std::array<uint32_t, 3>{1, 1, 1});
  CHECK(levels[2].downsample == std::array<uint32_t, 3>{4, 4, 4});
  auto c = (*s)->read({0, 2, 1, 0, 0, 0});
  REQUIRE(c.is_ok());
  const uint32_t e = (*c)->edge;
  CHECK(e == 36);
  // Payload voxel (i, j, k) is volume voxel (64 + i - 2, 32 + j - 2, k - 2), clamped into the volume.
  for (uint32_t k : {0u, 3u, 35u})
    for (uint32_t j : {0u, 1u, 2u, 35u})
      for (uint32_t i : {0u, 2u, 7u, 35u}) {
        const uint32_t x = std::min(69u, 62u + i), y = std::min(32u, 30u + j), z = std::min(4u, k < 2 ? 0u : k - 2);
        CHECK((*c)->data[(size_t(k) * e + j) * e + i] == v.data[(size_t(z) * 33 + y) * 70 + x]);
      }
  auto st = (*s)->stats({0, 2, 1, 0, 0, 0});
  REQUIRE(st.is_ok());
  const auto [lo, hi] = std::minmax_element((*c)->data.begin(), (*c)->data.end());
  CHECK(st->min == *lo);
  CHECK(st->max == *hi);
  CHECK((*s)->read({0, 3, 0, 0, 0, 0}).status().code() == ErrorCode::kNotFound);
}

TEST_CASE("pipeline cache: a file round-trips, a corrupt, truncated or foreign one is refused naming the file") {
  const std::string path = (std::filesystem::temp_directory_path() / "vxr_pipeline_cache_test/p.bin").string();
  VkPhysicalDeviceProperties props{};
  props.vendorID = 0x1234;
  props.deviceID = 0x42;
  for (uint32_t i = 0; i < VK_UUID_SIZE; ++i) props.pipelineCacheUUID[i] = uint8_t(i);
  std::vector<uint8_t> payload(64, 7);
  // The driver's header: length 32, version one, vendor, device, UUID.
  const uint32_t head[4] = {32, VK_PIPELINE_CACHE_HEADER_VERSION_ONE, props.vendorID, props.deviceID};
  std::memcpy(payload.data(), head, 16);
  std::memcpy(payload.data() + 16, props.pipelineCacheUUID, VK_UUID_SIZE);
  REQUIRE(gpu::write_pipeline_cache(path, props, payload).is_ok());
  auto back = gpu::read_pipeline_cache(path, props);
  REQUIRE(back.is_ok());
  CHECK(*back == payload);

  auto refused = [&](const char* why) {
    auto r = gpu::read_pipeline_cache(path, props);
    INFO(why);
    REQUIRE(!r.is_ok());
    CHECK(r.status().code() == ErrorCode::kCorrupt);
    CHECK(r.status().message().find(path) != std::string::npos);
  };
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(48 + 40);
    f.put(8);  // one payload byte flipped
  }
  refused("checksum");
  REQUIRE(gpu::write_pipeline_cache(path, props, payload).is_ok());
  std::filesystem::resize_file(path, 48 + 10);
  refused("truncated");
  VkPhysicalDeviceProperties other = props;
  other.pipelineCacheUUID[3] ^= 1;
  REQUIRE(gpu::write_pipeline_cache(path, other, payload).is_ok());
  refused("another driver");
  CHECK(gpu::read_pipeline_cache(path + ".missing", props).status().code() == ErrorCode::kNotFound);
}

#include <doctest/doctest.h>

#include <cstring>

#include "gpu/resources.h"
#include "gpu/shaders.h"
#include "gpu_fixture.h"

using namespace vxr;
using vxr::test::gpu_context;

TEST_CASE("gpu: validation layer is active (negative control: a deliberate API mistake is reported)") {
  gpu::Context& ctx = gpu_context();
  REQUIRE(ctx.validation_enabled());
  gpu::reset_validation_messages();
  // A zero-sized buffer violates VUID-VkBufferCreateInfo-size-00912.
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = 0;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  vkCreateBuffer(ctx.device(), &bci, nullptr, &buffer);
  if (buffer) vkDestroyBuffer(ctx.device(), buffer, nullptr);
  CHECK(gpu::validation_message_count() >= 1);
  CHECK(gpu::first_validation_message().find("size") != std::string::npos);
  gpu::reset_validation_messages();
}

TEST_CASE("gpu: device selection honours VXR_DEVICE and names the device") {
  vxr::test::GpuTestScope scope;
  gpu::Context& ctx = gpu_context();
  CHECK_FALSE(ctx.info().name.empty());
  CHECK(ctx.info().api_version >= VK_API_VERSION_1_3);
  gpu::ContextOptions o;
  o.device_filter = "no-such-device-xyz";
  auto r = gpu::Context::create(o);
  CHECK(r.status().code() == ErrorCode::kNotFound);
  CHECK(r.status().message().find("no-such-device-xyz") != std::string::npos);
}

TEST_CASE("gpu: image upload then readback returns the same bytes") {
  vxr::test::GpuTestScope scope;
  gpu::Context& ctx = gpu_context();
  auto img = gpu::create_image(ctx, {VK_IMAGE_TYPE_2D, VK_FORMAT_R8G8B8A8_UNORM, {13, 7, 1},
                                     VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
                                         VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                     "roundtrip"});
  REQUIRE(img.is_ok());
  std::vector<uint8_t> in(13 * 7 * 4), out(in.size());
  for (size_t i = 0; i < in.size(); ++i) in[i] = static_cast<uint8_t>(i * 13 + 5);
  REQUIRE(gpu::upload_image(ctx, *img, in.data(), in.size()).is_ok());
  REQUIRE(gpu::readback_image(ctx, *img, out.data(), out.size()).is_ok());
  CHECK(in == out);
}

TEST_CASE("gpu: images past the device limits are refused before Vulkan sees them") {
  vxr::test::GpuTestScope scope;
  gpu::Context& ctx = gpu_context();
  const uint32_t too_big = ctx.limits().maxImageDimension3D + 1;
  auto r = gpu::create_image(ctx, {VK_IMAGE_TYPE_3D, VK_FORMAT_R8_UNORM, {too_big, 4, 4}, VK_IMAGE_USAGE_SAMPLED_BIT,
                                   "too big"});
  CHECK(r.status().code() == ErrorCode::kOutOfRange);
  auto zero = gpu::create_image(ctx, {VK_IMAGE_TYPE_3D, VK_FORMAT_R8_UNORM, {0, 4, 4}, VK_IMAGE_USAGE_SAMPLED_BIT, "z"});
  CHECK(zero.status().code() == ErrorCode::kInvalidArgument);
}

TEST_CASE("gpu: shaders are embedded at build time and load as modules") {
  vxr::test::GpuTestScope scope;
  auto blob = gpu::find_shader("brick_raycast.comp");
  REQUIRE(blob.is_ok());
  CHECK(blob->word_count > 100);
  CHECK(blob->words[0] == 0x07230203u);  // SPIR-V magic
  CHECK(gpu::create_shader_module(gpu_context(), "brick_raycast.comp").is_ok());
  auto missing = gpu::find_shader("nope.comp");
  CHECK(missing.status().code() == ErrorCode::kNotFound);
}

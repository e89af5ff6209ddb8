// SPIR-V compiled from shaders_glsl/ at build time and embedded in the binary.
//
// Names are the GLSL file name without ".glsl": "brick_raycast.comp" is
// shaders_glsl/brick_raycast.comp.glsl. There is no runtime file lookup.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/status.h"
#include "gpu/context.h"
#include "gpu/handle.h"

namespace vxr::gpu {

struct SpirvBlob {
  const uint32_t* words = nullptr;
  size_t word_count = 0;
};

// The embedded blob for `name`, or kNotFound listing what exists.
Result<SpirvBlob> find_shader(std::string_view name);
std::vector<std::string_view> shader_names();

Result<Handle<VkShaderModule>> create_shader_module(const Context& ctx, std::string_view name);

}  // namespace vxr::gpu

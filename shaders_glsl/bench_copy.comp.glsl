#version 450
// Roofline calibration: the memory-bound ceiling. Streams vec4s from one
// storage buffer to another; bytes moved / time = achievable bandwidth.
// Each invocation copies kPerThread vec4s, strided by the grid size so that
// neighbouring invocations touch neighbouring memory: per-workgroup overhead
// (large on CPU drivers) is amortised without losing coalescing on GPUs.
layout(local_size_x = 256) in;
layout(constant_id = 0) const uint kPerThread = 16;
layout(std430, binding = 0) readonly buffer Src { vec4 src[]; };
layout(std430, binding = 1) writeonly buffer Dst { vec4 dst[]; };
layout(push_constant) uniform Push { uint count; } pc;

void main() {
  uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  for (uint k = 0; k < kPerThread; ++k) {
    uint i = gl_GlobalInvocationID.x + k * stride;
    if (i < pc.count) dst[i] = src[i];
  }
}

#version 450
// Roofline calibration: the sampling-bound ceiling. Each invocation marches a
// straight line through a 3D texture with trilinear fetches, like a ray
// caster with no transfer function or compositing; samples / time = the
// device's trilinear sampling rate for ray-like access.
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler3D volume_tex;
layout(std430, binding = 1) writeonly buffer Out { float result[]; };
layout(push_constant) uniform Push { uvec4 size_steps; } pc;  // x,y: grid, z: steps per invocation

void main() {
  uvec2 id = gl_GlobalInvocationID.xy;
  if (id.x >= pc.size_steps.x || id.y >= pc.size_steps.y) return;
  vec3 pos = vec3((vec2(id) + 0.5) / vec2(pc.size_steps.xy), 0.0);
  float dz = 1.0 / float(pc.size_steps.z);
  float acc = 0.0;
  for (uint i = 0; i < pc.size_steps.z; ++i) {
    acc += texture(volume_tex, vec3(pos.xy, (float(i) + 0.5) * dz)).r;
  }
  result[id.y * pc.size_steps.x + id.x] = acc;
}

// Wavefront OBJ surfaces (`vxr annotate import-obj`): whatever parses must
// describe a drawable mesh: every triangle's corners exist, every triangle
// has a material and lies in exactly one part, parents come before children.
#include <string>

#include "annotate/obj.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto r = vxr::annotate::parse_obj(text, "fuzz.obj", "");
  if (!r) return 0;
  const auto& m = r->mesh;
  if (m.triangles.empty() || m.triangle_material.size() != m.triangles.size()) __builtin_trap();
  for (const auto& t : m.triangles)
    for (uint32_t v : t)
      if (v >= m.positions.size()) __builtin_trap();
  for (uint32_t mat : m.triangle_material)
    if (mat >= m.materials.size()) __builtin_trap();
  uint64_t covered = 0;
  for (size_t i = 0; i < m.parts.size(); ++i) {
    const auto& p = m.parts[i];
    if (p.parent >= int(i)) __builtin_trap();
    if (uint64_t(p.first_triangle) + p.triangle_count > m.triangles.size()) __builtin_trap();
    covered += p.triangle_count;
  }
  if (covered != m.triangles.size()) __builtin_trap();
  return 0;
}

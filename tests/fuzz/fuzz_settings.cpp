// Render settings and scene JSON (`--settings`, `--scene` files). What parses
// must serialise and parse back to the same value.
#include <string>

#include "fuzz_util.h"
#include "scene/render_settings.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (auto s = vxr::render_settings_from_json(text)) {
    auto back = vxr::render_settings_from_json(vxr::render_settings_to_json(*s));
    if (!back || !(*back == *s)) __builtin_trap();
  }
  if (auto sc = vxr::scene_from_json(text)) {
    auto back = vxr::scene_from_json(vxr::scene_to_json(*sc));
    if (!back || !(*back == *sc)) __builtin_trap();
  }
  return 0;
}

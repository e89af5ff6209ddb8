// Files from assets/ compiled into the binary.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "core/status.h"
#include "volume/dense_volume.h"

namespace vxr::assets {

// The bytes of an embedded asset by its path under assets/, e.g.
// "mri-stack/volume.json"; nullopt if it was not embedded.
std::optional<std::span<const uint8_t>> find(std::string_view name);

// The bundled sample volume (the MRI head, assets/mri-stack/).
Result<DenseVolume> sample_volume();

}  // namespace vxr::assets

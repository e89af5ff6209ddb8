#include <nlohmann/json.hpp>

#include "assets/assets.h"

namespace vxr::assets {

Result<DenseVolume> sample_volume() {
  auto meta = find("mri-stack/volume.json");
  auto raw = find("mri-stack/mri-stack.u8.raw");
  if (!meta || !raw) return internal_error("the sample volume was not embedded in this build");
  const auto j = nlohmann::json::parse(meta->begin(), meta->end(), nullptr, false);
  if (j.is_discarded()) return internal_error("embedded mri-stack/volume.json is not JSON");
  DenseVolume v;
  const auto dims = j["dims"].get<std::vector<uint32_t>>();
  const auto vs = j["voxel_size"].get<std::vector<double>>();
  v.dims = {dims[0], dims[1], dims[2]};
  v.voxel_size = {vs[0], vs[1], vs[2]};
  v.unit = j["unit"].get<std::string>();
  v.dtype = DType::kU8;
  if (raw->size() != v.byte_size()) return internal_error("embedded sample volume has the wrong size");
  v.data.assign(raw->begin(), raw->end());
  return v;
}

}  // namespace vxr::assets

#include "volume/dense_volume.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace vxr {

Status check_renderable(const DenseVolume& v) {
  if (v.dims[0] == 0 || v.dims[1] == 0 || v.dims[2] == 0)
    return invalid_argument("volume is " + std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" +
                            std::to_string(v.dims[2]) + " voxels: a zero side leaves nothing to render");
  for (int a = 0; a < 3; ++a) {
    if (!(v.voxel_size[a] > 0.0) || !std::isfinite(v.voxel_size[a]))
      return invalid_argument("volume voxel_size[" + std::to_string(a) + "] is " + std::to_string(v.voxel_size[a]) +
                              ": voxel sizes must be positive finite numbers");
    if (!std::isfinite(v.origin[a])) return invalid_argument("volume origin must be finite");
  }
  if (v.data.size() != v.byte_size()) return invalid_argument("volume data size does not match its dims and dtype");
  return Status::ok();
}

const char* dtype_name(DType t) {
  switch (t) {
    case DType::kU8: return "u8";
    case DType::kI8: return "i8";
    case DType::kU16: return "u16";
    case DType::kI16: return "i16";
    case DType::kU32: return "u32";
    case DType::kI32: return "i32";
    case DType::kF32: return "f32";
  }
  return "?";
}

std::optional<DType> dtype_from_name(std::string_view name) {
  for (DType t : {DType::kU8, DType::kI8, DType::kU16, DType::kI16, DType::kU32, DType::kI32, DType::kF32})
    if (name == dtype_name(t)) return t;
  return std::nullopt;
}

double decode_voxel(const uint8_t* p, DType t) {
  switch (t) {
    case DType::kU8: return *p;
    case DType::kI8: return static_cast<int8_t>(*p);
    case DType::kU16: { uint16_t v; std::memcpy(&v, p, 2); return v; }
    case DType::kI16: { int16_t v; std::memcpy(&v, p, 2); return v; }
    case DType::kU32: { uint32_t v; std::memcpy(&v, p, 4); return v; }
    case DType::kI32: { int32_t v; std::memcpy(&v, p, 4); return v; }
    case DType::kF32: { float v; std::memcpy(&v, p, 4); return v; }
  }
  return 0.0;
}

double DenseVolume::value_at(uint32_t x, uint32_t y, uint32_t z) const {
  const uint64_t i = (uint64_t(z) * dims[1] + y) * dims[0] + x;
  return decode_voxel(data.data() + i * dtype_bytes(dtype), dtype);
}

Result<DenseVolume> load_raw_volume(const std::string& json_path) {
  std::ifstream f(json_path);
  if (!f) return not_found(json_path + ": cannot open");
  nlohmann::json j = nlohmann::json::parse(f, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return invalid_argument(json_path + ": not a JSON object");
  DenseVolume v;
  try {
    const auto dims = j.at("dims").get<std::vector<uint32_t>>();
    if (dims.size() != 3 || !dims[0] || !dims[1] || !dims[2])
      return invalid_argument(json_path + ": \"dims\" must be three positive integers");
    v.dims = {dims[0], dims[1], dims[2]};
    auto dt = dtype_from_name(j.at("dtype").get<std::string>());
    if (!dt) return invalid_argument(json_path + ": unknown \"dtype\" (use u8, i8, u16, i16, u32, i32, f32)");
    v.dtype = *dt;
    if (j.contains("voxel_size")) {
      const auto vs = j["voxel_size"].get<std::vector<double>>();
      if (vs.size() != 3 || vs[0] <= 0 || vs[1] <= 0 || vs[2] <= 0)
        return invalid_argument(json_path + ": \"voxel_size\" must be three positive numbers");
      v.voxel_size = {vs[0], vs[1], vs[2]};
    }
    if (j.contains("unit")) v.unit = j["unit"].get<std::string>();
    const auto raw_path = std::filesystem::path(json_path).parent_path() / j.at("file").get<std::string>();
    std::ifstream rf(raw_path, std::ios::binary);
    if (!rf) return not_found(raw_path.string() + ": cannot open (named by " + json_path + ")");
    v.data.resize(v.byte_size());
    rf.read(reinterpret_cast<char*>(v.data.data()), static_cast<std::streamsize>(v.data.size()));
    if (static_cast<uint64_t>(rf.gcount()) != v.data.size() || rf.peek() != EOF)
      return corrupt(raw_path.string() + ": size does not match dims x dtype in " + json_path);
  } catch (const nlohmann::json::exception& e) {
    return invalid_argument(json_path + ": " + e.what());
  }
  return v;
}

}  // namespace vxr

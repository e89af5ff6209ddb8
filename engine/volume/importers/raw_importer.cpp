#include "volume/importers/raw_importer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/checked_math.h"
#include "core/json_number.h"

namespace vxr {
namespace {

class RawSource final : public SlabSource {
 public:
  RawSource(VolumeInfo info, std::string path, bool swap) : info_(std::move(info)), path_(std::move(path)), swap_(swap) {}

  const VolumeInfo& info() const override { return info_; }
  std::string format_name() const override { return "raw volume with JSON sidecar"; }
  std::vector<std::string> files() const override { return {path_}; }

  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override {
    const uint32_t bpv = dtype_bytes(info_.dtype);
    if (dst.size() != box.voxels() * bpv) return invalid_argument(path_ + ": read_region buffer has the wrong size");
    for (int a = 0; a < 3; ++a)
      if (box.origin[a] + box.size[a] > info_.dims[a]) return out_of_range(path_ + ": region outside the volume");
    std::lock_guard<std::mutex> lock(mutex_);
    if (!file_.is_open()) {
      file_.open(path_, std::ios::binary);
      if (!file_) return io_error(path_ + ": cannot open");
    }
    const uint64_t vol_bytes = info_.voxels_per_volume() * bpv;
    const uint64_t base = (uint64_t(timepoint) * info_.channels + channel) * vol_bytes;
    const uint64_t row = box.size[0] * bpv;
    uint8_t* out = dst.data();
    for (uint64_t z = 0; z < box.size[2]; ++z) {
      for (uint64_t y = 0; y < box.size[1]; ++y) {
        const uint64_t off =
            base + (((box.origin[2] + z) * info_.dims[1] + box.origin[1] + y) * info_.dims[0] + box.origin[0]) * bpv;
        file_.seekg(static_cast<std::streamoff>(off));
        file_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(row));
        if (static_cast<uint64_t>(file_.gcount()) != row) {
          file_.clear();
          return corrupt(path_ + ": file is shorter than its sidecar's dims say");
        }
        out += row;
      }
    }
    if (swap_ && bpv > 1)
      for (uint8_t* p = dst.data(); p < dst.data() + dst.size(); p += bpv) std::reverse(p, p + bpv);
    return Status::ok();
  }

 private:
  VolumeInfo info_;
  std::string path_;
  bool swap_;
  std::mutex mutex_;
  std::ifstream file_;
};

}  // namespace

Result<std::unique_ptr<SlabSource>> open_raw_import(const std::string& json_path) {
  std::ifstream f(json_path);
  if (!f) return not_found(json_path + ": cannot open");
  const nlohmann::json j = nlohmann::json::parse(f, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return invalid_argument(json_path + ": not a JSON object");
  VolumeInfo info;
  std::string raw;
  bool swap = false;
  try {
    const nlohmann::json& jd = j.at("dims");
    std::optional<uint64_t> dims[3];
    if (jd.is_array() && jd.size() == 3)
      for (int a = 0; a < 3; ++a) dims[a] = json_number<uint64_t>(jd[a]);
    if (!dims[0] || !dims[1] || !dims[2] || !*dims[0] || !*dims[1] || !*dims[2])
      return invalid_argument(json_path + ": \"dims\" must be three positive integers");
    info.dims = {*dims[0], *dims[1], *dims[2]};
    auto dt = dtype_from_name(j.at("dtype").get<std::string>());
    if (!dt) return invalid_argument(json_path + ": unknown \"dtype\" (use u8, i8, u16, i16, u32, i32, f32)");
    info.dtype = *dt;
    const auto channels = j.contains("channels") ? json_number<uint32_t>(j["channels"]) : std::optional<uint32_t>(1);
    const auto timepoints = j.contains("timepoints") ? json_number<uint32_t>(j["timepoints"]) : std::optional<uint32_t>(1);
    if (!channels || !timepoints || !*channels || !*timepoints)
      return invalid_argument(json_path + ": \"channels\" and \"timepoints\" must be integers >= 1");
    info.channels = *channels;
    info.timepoints = *timepoints;
    if (j.contains("voxel_size")) {
      const auto vs = j["voxel_size"].get<std::vector<double>>();
      if (vs.size() != 3 || !(vs[0] > 0) || !(vs[1] > 0) || !(vs[2] > 0) || !std::isfinite(vs[0]) ||
          !std::isfinite(vs[1]) || !std::isfinite(vs[2]))
        return invalid_argument(json_path + ": \"voxel_size\" must be three positive numbers");
      info.voxel_size = {vs[0], vs[1], vs[2]};
    }
    info.unit = j.value("unit", std::string("um"));
    const std::string endian = j.value("endian", std::string("little"));
    if (endian != "little" && endian != "big") return invalid_argument(json_path + ": \"endian\" must be little or big");
    swap = endian == "big";
    raw = (std::filesystem::path(json_path).parent_path() / j.at("file").get<std::string>()).string();
  } catch (const nlohmann::json::exception& e) {
    return invalid_argument(json_path + ": " + e.what());
  }
  std::error_code ec;
  // The dims must describe the raw file's size exactly; checked so that huge
  // dims cannot wrap around to match it.
  const auto need = checked_product({info.dims[0], info.dims[1], info.dims[2], dtype_bytes(info.dtype), info.channels,
                                     info.timepoints});
  if (!need || *need > (uint64_t(1) << 56))
    return out_of_range(json_path + ": \"dims\" " + std::to_string(info.dims[0]) + " x " + std::to_string(info.dims[1]) +
                        " x " + std::to_string(info.dims[2]) + " (with channels and timepoints) describe more bytes than "
                        "any file holds; fix the sidecar");
  const uint64_t have = std::filesystem::file_size(raw, ec);
  if (ec) return not_found(raw + ": cannot open (named by " + json_path + ")");
  if (have != *need)
    return corrupt(raw + ": has " + std::to_string(have) + " bytes, but " + json_path + " describes " +
                   std::to_string(*need));
  return std::unique_ptr<SlabSource>(new RawSource(std::move(info), raw, swap));
}

}  // namespace vxr

#include "gpu/pipeline_cache.h"

#include "core/output_file.h"

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace vxr::gpu {
namespace {

constexpr char kMagic[8] = {'V', 'X', 'R', 'P', 'C', 'v', '1', '\0'};

struct FileHeader {
  char magic[8];
  uint32_t vendor_id;
  uint32_t device_id;
  uint8_t uuid[VK_UUID_SIZE];
  uint64_t payload_bytes;
  uint64_t payload_hash;  // FNV-1a 64
};
static_assert(sizeof(FileHeader) == 48, "pipeline cache header layout");

uint64_t fnv1a(const uint8_t* p, size_t n) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

}  // namespace

std::string pipeline_cache_path() {
  if (const char* p = std::getenv("VXR_PIPELINE_CACHE"); p && *p) return std::string(p) == "off" ? "" : p;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/vxr/pipelines.bin";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/vxr/pipelines.bin";
  return "";
}

Result<std::vector<uint8_t>> read_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return not_found(path + ": no pipeline cache yet");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  auto refuse = [&](const std::string& why) {
    return corrupt(path + ": pipeline cache refused (" + why + "); starting empty, it is rewritten at exit");
  };
  FileHeader h;
  if (bytes.size() < sizeof(h)) return refuse("shorter than its header");
  std::memcpy(&h, bytes.data(), sizeof(h));
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0) return refuse("not a vxr pipeline cache");
  if (h.vendor_id != props.vendorID || h.device_id != props.deviceID ||
      std::memcmp(h.uuid, props.pipelineCacheUUID, VK_UUID_SIZE) != 0)
    return refuse("written for another device or driver version");
  if (h.payload_bytes != bytes.size() - sizeof(h)) return refuse("truncated or padded");
  const uint8_t* payload = bytes.data() + sizeof(h);
  if (fnv1a(payload, h.payload_bytes) != h.payload_hash) return refuse("checksum mismatch");
  // The driver's own header (VkPipelineCacheHeaderVersionOne) must agree too.
  if (h.payload_bytes < 32) return refuse("driver header missing");
  uint32_t len, version, vendor, device;
  std::memcpy(&len, payload, 4);
  std::memcpy(&version, payload + 4, 4);
  std::memcpy(&vendor, payload + 8, 4);
  std::memcpy(&device, payload + 12, 4);
  if (len < 32 || version != VK_PIPELINE_CACHE_HEADER_VERSION_ONE || vendor != props.vendorID ||
      device != props.deviceID || std::memcmp(payload + 16, props.pipelineCacheUUID, VK_UUID_SIZE) != 0)
    return refuse("driver header does not match this device");
  return std::vector<uint8_t>(payload, payload + h.payload_bytes);
}

Status write_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                            const std::vector<uint8_t>& payload) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path target(path);
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  FileHeader h{};
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  h.vendor_id = props.vendorID;
  h.device_id = props.deviceID;
  std::memcpy(h.uuid, props.pipelineCacheUUID, VK_UUID_SIZE);
  h.payload_bytes = payload.size();
  h.payload_hash = fnv1a(payload.data(), payload.size());
  // Header and payload in one buffer, written through a TempFile: never torn, never through a planted link.
  std::vector<uint8_t> bytes(sizeof(h) + payload.size());
  std::memcpy(bytes.data(), &h, sizeof(h));
  if (!payload.empty()) std::memcpy(bytes.data() + sizeof(h), payload.data(), payload.size());
  VXR_RETURN_IF_ERROR(write_file_atomically(path, bytes));
  return Status::ok();
}

}  // namespace vxr::gpu

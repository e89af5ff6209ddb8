#include "volume/open_chunk_source.h"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "volume/container_format.h"
#include "volume/container_reader.h"
#include "volume/zarr/zarr_chunk_source.h"

namespace vxr {

namespace {
// A container renamed to another extension still starts with the file magic.
bool starts_with_container_magic(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[sizeof vxc::kFileMagic] = {};
  return in.read(magic, sizeof magic) && std::memcmp(magic, vxc::kFileMagic, sizeof magic) == 0;
}
}  // namespace

bool is_chunk_source_input(const std::string& path) {
  std::error_code ec;
  return std::filesystem::path(path).extension() == ".vxc" || zarr::looks_like_zarr(path) ||
         (std::filesystem::is_regular_file(path, ec) && starts_with_container_magic(path));
}

Result<OpenedChunkSource> open_chunk_source(const std::string& path) {
  OpenedChunkSource out;
  if (zarr::looks_like_zarr(path)) {
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<ZarrChunkSource> z, ZarrChunkSource::open(path));
    const auto& img = z->image();
    out.format = (img.version().empty() ? std::string("Zarr array") : "OME-Zarr " + img.version()) + " (Zarr v" +
                 std::to_string(img.zarr_format()) + ")";
    out.warnings = z->warnings();
    out.source = std::move(z);
    return out;
  }
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<ContainerReader> r, ContainerReader::open(path));
  out.format = "vxc container";
  out.source = std::move(r);
  return out;
}

}  // namespace vxr

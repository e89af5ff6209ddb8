#include "volume/importers/import_source.h"

#include <cmath>
#include <filesystem>

#include "core/output_file.h"

#include "volume/importers/imaris_importer.h"
#include "volume/importers/import_limits.h"
#include "volume/importers/ome_tiff_importer.h"
#include "volume/importers/ome_zarr_importer.h"
#include "volume/importers/picture_decoder.h"
#include "volume/importers/raw_importer.h"
#include "volume/importers/slice_series_importer.h"
#include "volume/importers/tiff_importer.h"
#include "volume/importers/tiff_reader.h"
#include "volume/zarr/ome_zarr.h"

namespace vxr {
namespace {

std::string extension_lower(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool ends_with_lower(const std::string& path, std::string_view suffix) {
  std::string l = path;
  for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return l.size() >= suffix.size() && l.compare(l.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string without_trailing_slashes(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  return path;
}

// One file: pick the importer by content first, then by name.
Result<std::unique_ptr<SlabSource>> open_one_file(const std::string& path) {
  VXR_RETURN_IF_ERROR(check_input(path));  // a FIFO or device would block or never end
  const std::string ext = extension_lower(path);
  if (ext == ".json") return open_raw_import(path);
  if (tiff::has_tiff_magic(path)) return open_tiff_import(path);
  if (has_hdf5_magic(path)) return open_imaris_import(path);
  if (ends_with_lower(path, ".companion.ome") || ends_with_lower(path, ".ome.xml")) return open_ome_tiff_import(path);
  if (Result<PictureHeader> pic = probe_picture(path)) return open_slice_series_import({path});
  else if (pic.status().code() != ErrorCode::kUnsupported) return pic.status();
  if (ext == ".tif" || ext == ".tiff" || ext == ".btf" || ext == ".tf8")
    return invalid_argument(path + ": not a TIFF file (it does not start with a TIFF header II*/MM*)");
  if (ext == ".ims" || ext == ".h5")
    return invalid_argument(path + ": not an HDF5/Imaris file (no HDF5 signature)");
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
    return invalid_argument(path + ": not a " + ext.substr(1) + " file (wrong signature)");
  return unsupported(path + ": unrecognised input format (import reads TIFF, OME-TIFF, ImageJ TIFF, Imaris .ims, "
                     "PNG/JPEG slices, OME-Zarr folders, or raw+JSON)");
}


// Wraps a source to override metadata with what the user said.
class HintedSource final : public SlabSource {
 public:
  HintedSource(std::unique_ptr<SlabSource> inner, const ImportHints& hints) : inner_(std::move(inner)) {
    info_ = inner_->info();
    if (hints.voxel_size) info_.voxel_size = *hints.voxel_size;
    if (hints.unit) info_.unit = *hints.unit;
  }
  const VolumeInfo& info() const override { return info_; }
  Status read_region(uint32_t c, uint32_t t, const Box3& box, std::span<uint8_t> dst) override {
    return inner_->read_region(c, t, box, dst);
  }
  std::vector<std::string> warnings() const override { return inner_->warnings(); }
  std::string format_name() const override { return inner_->format_name(); }
  std::vector<std::string> files() const override { return inner_->files(); }

 private:
  std::unique_ptr<SlabSource> inner_;
  VolumeInfo info_;
};

}  // namespace

bool voxel_size_usable(const std::array<double, 3>& v) {
  double lo = INFINITY, hi = 0;
  for (double x : v) {
    if (!std::isfinite(x) || !(x > 0)) return false;
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return hi / lo <= 1e6;  // past that the volume is a sheet thinner than float precision can draw
}

Result<std::unique_ptr<SlabSource>> open_import_source(const std::vector<std::string>& inputs,
                                                       const ImportHints& hints) {
  if (inputs.empty()) return invalid_argument("no input files given");
  if (hints.memory_bytes) set_import_memory_budget(*hints.memory_bytes);
  const std::string& first = inputs.front();
  Result<std::unique_ptr<SlabSource>> source = unsupported(first + ": unrecognised input format");
  std::error_code ec;
  if (inputs.size() == 1 && zarr::looks_like_zarr(first)) {
    source = open_ome_zarr_import(first);
  } else if (inputs.size() == 1 && ends_with_lower(without_trailing_slashes(first), ".zarr") &&
             std::filesystem::is_directory(first, ec)) {
    return invalid_argument(first + ": named like a Zarr folder but holds no .zgroup, .zattrs, .zarray or zarr.json; "
                            "point at the OME-Zarr image folder");
  } else if (inputs.size() > 1 || std::filesystem::is_directory(first, ec) ||
      (!std::filesystem::exists(first, ec) && first.find_first_of("*?[") != std::string::npos)) {
    source = open_slice_series_import(inputs);
  } else if (!std::filesystem::exists(first, ec)) {
    return not_found(first + ": no such file or folder");
  } else {
    source = open_one_file(first);
  }
  if (!source) return source.status();
  // A zero, negative or non-finite size from a header would draw nothing (or NaN) later on.
  const auto& vs = (*source)->info().voxel_size;
  if (!hints.voxel_size && !voxel_size_usable(vs))
    return invalid_argument(first + ": the file gives a voxel size of " + std::to_string(vs[0]) + " x " +
                            std::to_string(vs[1]) + " x " + std::to_string(vs[2]) +
                            ", which vxr cannot draw; give the size with --voxel-size X,Y,Z");
  if (!hints.voxel_size && !hints.unit) return source;
  return std::unique_ptr<SlabSource>(new HintedSource(std::move(source).value(), hints));
}

}  // namespace vxr

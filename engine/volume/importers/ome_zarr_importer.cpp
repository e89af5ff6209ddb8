#include "volume/importers/ome_zarr_importer.h"

#include "volume/zarr/ome_zarr.h"

namespace vxr {
namespace {

class OmeZarrSlabSource final : public SlabSource {
 public:
  explicit OmeZarrSlabSource(std::unique_ptr<zarr::OmeZarrImage> image) : image_(std::move(image)) {}
  const VolumeInfo& info() const override { return image_->info(); }
  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override {
    for (int a = 0; a < 3; ++a)
      if (box.origin[a] > info().dims[a] || box.size[a] > info().dims[a] - box.origin[a])
        return out_of_range(image_->path() + ": read outside the image");
    if (dst.size() != box.voxels() * dtype_bytes(info().dtype))
      return invalid_argument(image_->path() + ": read buffer has the wrong size");
    return image_->read_region(0, channel, timepoint, box, dst);
  }
  std::vector<std::string> warnings() const override { return image_->warnings(); }
  std::vector<std::string> files() const override { return image_->metadata_files(); }
  std::string format_name() const override {
    const std::string v = image_->version().empty() ? "" : " " + image_->version();
    return image_->version().empty() ? "Zarr v" + std::to_string(image_->zarr_format()) + " array"
                                     : "OME-Zarr" + v + " (Zarr v" + std::to_string(image_->zarr_format()) + ")";
  }

 private:
  std::unique_ptr<zarr::OmeZarrImage> image_;
};

}  // namespace

Result<std::unique_ptr<SlabSource>> open_ome_zarr_import(const std::string& path) {
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<zarr::OmeZarrImage> image, zarr::OmeZarrImage::open(path));
  return std::unique_ptr<SlabSource>(new OmeZarrSlabSource(std::move(image)));
}

}  // namespace vxr

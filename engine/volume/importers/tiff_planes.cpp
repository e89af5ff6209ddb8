#include "volume/importers/tiff_planes.h"

#include <cstring>

namespace vxr {
namespace {
constexpr size_t kMaxPooledHandles = 32;
}

Result<std::unique_ptr<SlabSource>> TiffPlaneSource::create(TiffPlaneLayout layout, std::string format_name,
                                                            std::vector<std::string> warnings,
                                                            std::unique_ptr<tiff::TiffFile> first) {
  const VolumeInfo& info = layout.info;
  if (!info.dims[0] || !info.dims[1] || !info.dims[2] || !info.channels || !info.timepoints || !layout.samples ||
      info.channels % layout.samples)
    return internal_error("TIFF layout with an empty dimension");
  if (layout.planes.size() != uint64_t(info.dims[2]) * layout.plane_channels() * info.timepoints)
    return internal_error("TIFF layout plane count does not match its dimensions");
  bool any = false;
  for (const TiffPlane& pl : layout.planes) {
    if (pl.file < 0) continue;
    any = true;
    if (size_t(pl.file) >= layout.files.size() || pl.page >= layout.pages[pl.file].size())
      return internal_error("TIFF layout refers to a page that was not scanned");
    const tiff::PageInfo& p = layout.pages[pl.file][pl.page];
    if (p.width != info.dims[0] || p.height != info.dims[1] || p.channels() != layout.samples ||
        dtype_bytes(p.dtype) != dtype_bytes(info.dtype))
      return invalid_argument(layout.files[pl.file] + ": page " + std::to_string(pl.page) + " is " + p.shape_string() +
                              ", but the dataset is " + std::to_string(info.dims[0]) + "x" +
                              std::to_string(info.dims[1]) + ", " + std::to_string(layout.samples) + " x " +
                              dtype_name(info.dtype) + "; all planes must match");
  }
  if (!any) return invalid_argument(layout.files.empty() ? "TIFF dataset" : layout.files[0] + ": no image planes");
  std::unique_ptr<TiffPlaneSource> s(new TiffPlaneSource());
  s->layout_ = std::move(layout);
  s->format_ = std::move(format_name);
  s->warnings_ = std::move(warnings);
  if (first) s->release(0, std::move(first));
  return std::unique_ptr<SlabSource>(std::move(s));
}

Result<std::unique_ptr<tiff::TiffFile>> TiffPlaneSource::acquire(int32_t file) {
  {
    std::lock_guard<std::mutex> lock(pool_mutex_);
    auto it = pool_.find(file);
    if (it != pool_.end() && !it->second.empty()) {
      auto h = std::move(it->second.back());
      it->second.pop_back();
      --pooled_;
      return h;
    }
  }
  return tiff::TiffFile::open(layout_.files[file]);
}

void TiffPlaneSource::release(int32_t file, std::unique_ptr<tiff::TiffFile> handle) {
  std::lock_guard<std::mutex> lock(pool_mutex_);
  if (pooled_ >= kMaxPooledHandles) {
    // Drop handles of other files first, so a many-file dataset keeps few open.
    for (auto& [f, v] : pool_)
      if (f != file && !v.empty()) {
        v.pop_back();
        --pooled_;
        break;
      }
    if (pooled_ >= kMaxPooledHandles) return;  // handle closes here
  }
  pool_[file].push_back(std::move(handle));
  ++pooled_;
}

Status TiffPlaneSource::read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) {
  const VolumeInfo& info = layout_.info;
  const uint32_t ob = dtype_bytes(info.dtype);
  if (dst.size() != box.voxels() * ob) return invalid_argument("read_region: buffer has the wrong size");
  if (channel >= info.channels || timepoint >= info.timepoints) return out_of_range("read_region: no such channel/timepoint");
  for (int a = 0; a < 3; ++a)
    if (box.origin[a] + box.size[a] > info.dims[a] || box.size[a] == 0)
      return out_of_range("read_region: box outside the volume");
  const uint32_t pc = channel / layout_.samples, sample = channel % layout_.samples;
  const uint64_t plane_bytes = box.size[0] * box.size[1] * ob;
  for (uint64_t z = 0; z < box.size[2]; ++z) {
    uint8_t* out = dst.data() + z * plane_bytes;
    const TiffPlane pl = layout_.plane(uint32_t(box.origin[2] + z), pc, timepoint);
    if (pl.file < 0) {
      std::memset(out, 0, plane_bytes);
      continue;
    }
    VXR_ASSIGN_OR_RETURN(std::unique_ptr<tiff::TiffFile> h, acquire(pl.file));
    Status s = h->read_region(layout_.pages[pl.file][pl.page], sample, uint32_t(box.origin[0]),
                              uint32_t(box.origin[1]), uint32_t(box.size[0]), uint32_t(box.size[1]), out);
    release(pl.file, std::move(h));
    VXR_RETURN_IF_ERROR(s);
  }
  return Status::ok();
}

}  // namespace vxr

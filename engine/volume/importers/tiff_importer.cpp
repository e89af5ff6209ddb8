#include "volume/importers/tiff_importer.h"

#include <tiffio.h>

#include "volume/importers/imagej_metadata.h"
#include "volume/importers/ome_tiff_importer.h"
#include "volume/importers/tiff_planes.h"
#include "volume/importers/units.h"

namespace vxr {
namespace {

bool same_kind(const tiff::PageInfo& a, const tiff::PageInfo& b) {
  return a.width == b.width && a.height == b.height && a.channels() == b.channels() && a.dtype == b.dtype;
}

}  // namespace

PageCalibration page_calibration(const tiff::PageInfo& p, const std::string& imagej_unit) {
  PageCalibration c;
  if (!imagej_unit.empty()) {
    const auto unit = parse_length_unit(imagej_unit);
    if (!unit) return c;  // "pixel", "inch" in ImageJ means uncalibrated or print size
    c.unit = unit->name;
    c.x = p.x_resolution > 0 ? 1.0 / p.x_resolution : 1.0;
    c.y = p.y_resolution > 0 ? 1.0 / p.y_resolution : c.x;
    return c;
  }
  // Scientific writers (tifffile, Bio-Formats) use centimetres; inches are print DPI, not a sample size.
  if (p.resolution_unit == RESUNIT_CENTIMETER && p.x_resolution > 0) {
    c.unit = "um";
    c.x = 1e4 / p.x_resolution;
    c.y = p.y_resolution > 0 ? 1e4 / p.y_resolution : c.x;
  }
  return c;
}

Result<std::unique_ptr<SlabSource>> open_tiff_import(const std::string& path) {
  VXR_ASSIGN_OR_RETURN(std::unique_ptr<tiff::TiffFile> file, tiff::TiffFile::open(path));
  VXR_ASSIGN_OR_RETURN(std::vector<tiff::PageInfo> pages, file->scan_pages());
  const tiff::PageInfo p0 = pages.front();  // a copy: pages grows below
  if (looks_like_ome_xml(p0.description)) return open_ome_tiff_import(path);

  std::vector<std::string> warnings;
  std::vector<uint32_t> series;
  uint32_t reduced = 0;
  int64_t first_odd = -1;
  for (uint32_t i = 0; i < pages.size(); ++i) {
    if (i > 0 && pages[i].reduced) {
      ++reduced;
      continue;
    }
    if (!same_kind(pages[i], p0)) {
      first_odd = i;
      break;
    }
    series.push_back(i);
  }
  if (first_odd >= 0) {
    const uint64_t skipped = pages.size() - series.size();
    warnings.push_back(path + ": pages differ in size or type: imported the first series (" + p0.shape_string() +
                       ", " + std::to_string(series.size()) + (series.size() == 1 ? " page" : " pages") +
                       "); skipped " + std::to_string(skipped) + (skipped == 1 ? " page" : " pages") +
                       " (page " + std::to_string(first_odd) + " is " + pages[first_odd].shape_string() + ")");
  } else if (reduced > 0) {
    warnings.push_back(path + ": skipped " + std::to_string(reduced) + " reduced-resolution (thumbnail) pages");
  }
  if (p0.colormap && !p0.description.empty() && p0.description.rfind("ImageJ=", 0) == 0)
    warnings.push_back(path + ": palette (LUT) image: imported its colours as RGB");

  uint32_t n = uint32_t(series.size());
  uint32_t C = 1, Z = n, T = 1;
  std::string format = n == 1 ? "TIFF image" : "TIFF stack";
  const std::optional<ImageJMetadata> ij = parse_imagej_description(p0.description);
  if (ij) {
    format = "ImageJ TIFF";
    const uint64_t czt = uint64_t(ij->channels) * ij->slices * ij->frames;
    if (czt == n) {
      C = ij->channels, Z = ij->slices, T = ij->frames;
      if (C > 1 || T > 1) format = "ImageJ hyperstack TIFF";
    } else if (n == 1 && ij->images > 1 && uint64_t(ij->channels) * ij->slices * ij->frames == ij->images) {
      // ImageJ over 4 GB: one IFD, the other planes stored right after the first.
      const std::optional<uint64_t> base = file->contiguous_data_offset(p0);
      const uint64_t plane = (uint64_t(p0.width) * p0.spp * p0.bps + 7) / 8 * p0.height;
      if (!base || *base + plane * ij->images > file->file_size())
        return corrupt(path + ": ImageJ metadata says " + std::to_string(ij->images) +
                       " images stored after the first page, but the file is too short or the first page is not "
                       "stored contiguously; the file is truncated or damaged");
      for (uint32_t i = 1; i < ij->images; ++i) {
        tiff::PageInfo v = p0;
        v.raw_offset = *base + plane * i;
        v.description.clear();
        series.push_back(uint32_t(pages.size()));
        pages.push_back(std::move(v));
      }
      n = ij->images;
      C = ij->channels, Z = ij->slices, T = ij->frames;
      format = "ImageJ TIFF (over 4 GB, contiguous planes)";
    } else if (ij->images > n) {
      warnings.push_back(path + ": ImageJ metadata says " + std::to_string(ij->images) + " images but the file holds " +
                         std::to_string(n) + " pages; imported the pages as a z stack");
    } else if (czt != 1) {
      warnings.push_back(path + ": ImageJ metadata (channels=" + std::to_string(ij->channels) +
                         " slices=" + std::to_string(ij->slices) + " frames=" + std::to_string(ij->frames) +
                         ") does not match the " + std::to_string(n) + " pages; imported them as a z stack");
    }
  }

  TiffPlaneLayout layout;
  layout.files = {path};
  layout.samples = p0.channels();
  layout.info.dims = {p0.width, p0.height, Z};
  layout.info.dtype = p0.dtype;
  layout.info.channels = C * layout.samples;
  layout.info.timepoints = T;
  const PageCalibration cal = page_calibration(p0, ij ? ij->unit : std::string());
  layout.info.unit = cal.unit;
  layout.info.voxel_size = {cal.x, cal.y, cal.unit == "px" ? 1.0 : (ij ? ij->spacing : 1.0)};
  layout.pages = {std::move(pages)};
  layout.planes.resize(uint64_t(n));
  // ImageJ plane order is XYCZT: channel fastest.
  for (uint32_t t = 0; t < T; ++t)
    for (uint32_t z = 0; z < Z; ++z)
      for (uint32_t c = 0; c < C; ++c) layout.plane(z, c, t) = TiffPlane{0, series[(uint64_t(t) * Z + z) * C + c]};
  return TiffPlaneSource::create(std::move(layout), format, std::move(warnings), std::move(file));
}

}  // namespace vxr

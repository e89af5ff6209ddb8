#include "volume/importers/slice_series_importer.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <list>
#include <mutex>

#include "volume/importers/imagej_metadata.h"
#include "volume/importers/picture_decoder.h"
#include "volume/importers/tiff_importer.h"
#include "volume/importers/tiff_planes.h"
#include "volume/importers/tiff_reader.h"

namespace vxr {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string_view s) {
  std::string l(s);
  for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return l;
}

// PNG/JPEG slices: each slice decodes whole (the formats have no random
// access); a few decoded slices are kept so chunk-sized reads do not decode
// the same slice again and again.
class PictureSliceSource final : public SlabSource {
 public:
  PictureSliceSource(VolumeInfo info, std::vector<std::string> files, PictureHeader header)
      : info_(std::move(info)), files_(std::move(files)), header_(header) {}

  const VolumeInfo& info() const override { return info_; }
  std::vector<std::string> files() const override { return files_; }
  std::string format_name() const override {
    return std::string(header_.format == PictureFormat::kPng ? "PNG" : "JPEG") + " slice series";
  }

  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override {
    const uint32_t ob = dtype_bytes(info_.dtype);
    if (dst.size() != box.voxels() * ob) return invalid_argument("read_region: buffer has the wrong size");
    if (channel >= info_.channels || timepoint >= info_.timepoints) return out_of_range("read_region: no such channel");
    for (int a = 0; a < 3; ++a)
      if (box.origin[a] + box.size[a] > info_.dims[a] || box.size[a] == 0)
        return out_of_range("read_region: box outside the volume");
    const uint32_t nc = info_.channels;
    uint8_t* out = dst.data();
    for (uint64_t z = box.origin[2]; z < box.origin[2] + box.size[2]; ++z) {
      VXR_ASSIGN_OR_RETURN(std::shared_ptr<const std::vector<uint8_t>> slice, get(uint32_t(z)));
      for (uint64_t y = box.origin[1]; y < box.origin[1] + box.size[1]; ++y) {
        const uint8_t* row = slice->data() + (y * info_.dims[0] + box.origin[0]) * nc * ob;
        for (uint64_t x = 0; x < box.size[0]; ++x, out += ob) std::memcpy(out, row + (x * nc + channel) * ob, ob);
      }
    }
    return Status::ok();
  }

 private:
  Result<std::shared_ptr<const std::vector<uint8_t>>> get(uint32_t z) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto it = cache_.begin(); it != cache_.end(); ++it)
        if (it->first == z) {
          cache_.splice(cache_.begin(), cache_, it);
          return cache_.front().second;
        }
    }
    auto data = std::make_shared<std::vector<uint8_t>>();
    VXR_RETURN_IF_ERROR(decode_picture(files_[z], header_, *data));
    std::lock_guard<std::mutex> lock(mutex_);
    cache_.emplace_front(z, data);
    const size_t slice_bytes = data->size();
    const size_t keep = std::max<size_t>(2, (64u << 20) / std::max<size_t>(1, slice_bytes));
    while (cache_.size() > keep) cache_.pop_back();
    return std::shared_ptr<const std::vector<uint8_t>>(data);
  }

  VolumeInfo info_;
  std::vector<std::string> files_;
  PictureHeader header_;
  std::mutex mutex_;
  std::list<std::pair<uint32_t, std::shared_ptr<const std::vector<uint8_t>>>> cache_;
};

Result<std::vector<std::string>> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  if (inputs.size() == 1) {
    const std::string& in = inputs[0];
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      for (const fs::directory_entry& e : fs::directory_iterator(in, ec)) {
        const std::string name = e.path().filename().string();
        if (name.empty() || name[0] == '.' || !e.is_regular_file(ec) || !is_slice_file_name(name)) continue;
        files.push_back(e.path().string());
      }
      if (ec) return io_error(in + ": cannot list the folder (" + ec.message() + ")");
      if (files.empty()) return not_found(in + ": folder holds no .tif/.tiff/.png/.jpg/.jpeg slices");
    } else if (in.find_first_of("*?[") != std::string::npos) {
      glob_t g;
      std::memset(&g, 0, sizeof g);
      const int rc = ::glob(in.c_str(), 0, nullptr, &g);
      for (size_t i = 0; rc == 0 && i < g.gl_pathc; ++i)
        if (fs::is_regular_file(g.gl_pathv[i], ec)) files.push_back(g.gl_pathv[i]);
      globfree(&g);
      if (files.empty()) return not_found(in + ": pattern matches no files");
    } else {
      files.push_back(in);
    }
  } else {
    files = inputs;
  }
  std::sort(files.begin(), files.end(), [](const std::string& a, const std::string& b) {
    return natural_less(fs::path(a).filename().string(), fs::path(b).filename().string()) ||
           (!natural_less(fs::path(b).filename().string(), fs::path(a).filename().string()) && a < b);
  });
  return files;
}

}  // namespace

bool is_slice_file_name(std::string_view name) {
  const std::string l = lower(name);
  for (const char* ext : {".tif", ".tiff", ".png", ".jpg", ".jpeg"}) {
    const size_t n = std::strlen(ext);
    if (l.size() > n && l.compare(l.size() - n, n, ext) == 0) return true;
  }
  return false;
}

bool natural_less(std::string_view a, std::string_view b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])), db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string_view na = a.substr(i, ie - i), nb = b.substr(j, je - j);
      while (na.size() > 1 && na[0] == '0') na.remove_prefix(1);
      while (nb.size() > 1 && nb[0] == '0') nb.remove_prefix(1);
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      i = ie, j = je;
      continue;
    }
    const int ca = std::tolower(static_cast<unsigned char>(a[i])), cb = std::tolower(static_cast<unsigned char>(b[j]));
    if (ca != cb) return ca < cb;
    ++i, ++j;
  }
  return (a.size() - i) < (b.size() - j);
}

Result<std::unique_ptr<SlabSource>> open_slice_series_import(const std::vector<std::string>& inputs) {
  VXR_ASSIGN_OR_RETURN(std::vector<std::string> files, expand_inputs(inputs));
  const bool first_is_tiff = tiff::has_tiff_magic(files[0]);
  auto mismatch = [&](const std::string& odd, const std::string& what, const std::string& first_what) {
    return invalid_argument(odd + ": is " + what + ", but the first slice " + files[0] + " is " + first_what +
                            "; all slices must have the same size, channels and type");
  };

  if (first_is_tiff) {
    TiffPlaneLayout layout;
    layout.files = files;
    std::unique_ptr<tiff::TiffFile> first_handle;
    std::vector<std::string> warnings;
    for (size_t i = 0; i < files.size(); ++i) {
      if (!tiff::has_tiff_magic(files[i]))
        return invalid_argument(files[i] + ": not a TIFF file, but the first slice " + files[0] + " is");
      VXR_ASSIGN_OR_RETURN(std::unique_ptr<tiff::TiffFile> f, tiff::TiffFile::open(files[i]));
      VXR_ASSIGN_OR_RETURN(tiff::PageInfo p, f->describe_current(0));
      if (i > 0) {
        const tiff::PageInfo& p0 = layout.pages[0][0];
        if (p.width != p0.width || p.height != p0.height || p.channels() != p0.channels() || p.dtype != p0.dtype)
          return mismatch(files[i], p.shape_string(), p0.shape_string());
      }
      layout.pages.push_back({std::move(p)});
      if (i == 0) first_handle = std::move(f);
    }
    const tiff::PageInfo& p0 = layout.pages[0][0];
    layout.samples = p0.channels();
    layout.info.dims = {p0.width, p0.height, files.size()};
    layout.info.dtype = p0.dtype;
    layout.info.channels = layout.samples;
    const auto ij = parse_imagej_description(p0.description);
    const PageCalibration cal = page_calibration(p0, ij ? ij->unit : std::string());
    layout.info.unit = cal.unit;
    layout.info.voxel_size = {cal.x, cal.y, cal.unit == "px" ? 1.0 : (ij ? ij->spacing : 1.0)};
    for (size_t i = 0; i < files.size(); ++i) layout.planes.push_back(TiffPlane{int32_t(i), 0});
    return TiffPlaneSource::create(std::move(layout), "TIFF slice series", std::move(warnings), std::move(first_handle));
  }

  PictureHeader h0;
  std::vector<std::string> shapes;
  auto describe = [](const PictureHeader& h) {
    return std::to_string(h.width) + "x" + std::to_string(h.height) + ", " + std::to_string(h.channels) + " x " +
           dtype_name(h.dtype);
  };
  for (size_t i = 0; i < files.size(); ++i) {
    Result<PictureHeader> h = probe_picture(files[i]);
    if (!h) {
      if (h.status().code() == ErrorCode::kUnsupported && files.size() > 1)
        return invalid_argument(files[i] + ": not a PNG or JPEG file, but the first slice " + files[0] + " is");
      return h.status();
    }
    if (i == 0) {
      h0 = *h;
    } else if (h->width != h0.width || h->height != h0.height || h->channels != h0.channels || h->dtype != h0.dtype) {
      return mismatch(files[i], describe(*h), describe(h0));
    }
  }
  VolumeInfo info;
  info.dims = {h0.width, h0.height, files.size()};
  info.dtype = h0.dtype;
  info.channels = h0.channels;
  info.unit = "px";
  return std::unique_ptr<SlabSource>(new PictureSliceSource(std::move(info), std::move(files), h0));
}

}  // namespace vxr

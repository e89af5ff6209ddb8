#include "volume/importers/imaris_importer.h"

#include "core/checked_math.h"

#include <hdf5.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>

#include <sstream>

#include "volume/channel_display.h"
#include "volume/importers/units.h"

namespace vxr {
namespace {

constexpr H5Z_filter_t kLz4Filter = 32004;

std::mutex& hdf5_mutex() {
  static std::mutex m;
  return m;
}

// Closes an HDF5 id with the right function when it goes out of scope.
class Hid {
 public:
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hid() {
    if (id_ >= 0) close_(id_);
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

bool exists(hid_t loc, const std::string& path) {
  // H5Lexists fails on a missing intermediate group, so test each step.
  size_t pos = 0;
  while (true) {
    const size_t slash = path.find('/', pos);
    const std::string prefix = path.substr(0, slash);
    if (H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
    pos = slash + 1;
  }
}

// An attribute as text: Imaris writes char arrays (one element per character);
// other writers use fixed or variable-length strings.
std::optional<std::string> attr_string(hid_t file, const std::string& obj, const char* name) {
  if (!exists(file, obj) || H5Aexists_by_name(file, obj.c_str(), name, H5P_DEFAULT) <= 0) return std::nullopt;
  Hid attr(H5Aopen_by_name(file, obj.c_str(), name, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.ok()) return std::nullopt;
  Hid type(H5Aget_type(attr.get()), H5Tclose);
  Hid space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Tget_class(type.get()) != H5T_STRING) return std::nullopt;
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n <= 0 || n > (1 << 20)) return std::nullopt;
  if (H5Tis_variable_str(type.get()) > 0) {
    std::vector<char*> ptrs(size_t(n), nullptr);
    Hid mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), H5T_VARIABLE);
    if (H5Aread(attr.get(), mem.get(), ptrs.data()) < 0) return std::nullopt;
    std::string s = ptrs[0] ? ptrs[0] : "";
    H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, ptrs.data());
    return s;
  }
  // Sizes from the file: refuse a text attribute over 1 MiB before allocating it.
  const auto bytes = checked_product({uint64_t(n), uint64_t(H5Tget_size(type.get()))});
  if (!bytes || *bytes == 0 || *bytes > (uint64_t(1) << 20)) return std::nullopt;
  const size_t size = H5Tget_size(type.get());
  std::vector<char> buf(*bytes + 1, 0);
  if (H5Aread(attr.get(), type.get(), buf.data()) < 0) return std::nullopt;
  std::string s;
  for (size_t i = 0; i < size_t(n) * size; ++i)
    if (buf[i]) s += buf[i];
  return s;
}

std::optional<double> attr_number(hid_t file, const std::string& obj, const char* name) {
  const auto s = attr_string(file, obj, name);
  if (!s) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(s->c_str(), &end);
  if (end == s->c_str() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// DataSetInfo/Channel c: Name, Color "r g b" (0..1) and ColorRange "lo hi"
// (the display window); empty when no channel states any of them.
std::vector<ChannelDisplay> imaris_channel_display(hid_t file, uint32_t channels) {
  std::vector<ChannelDisplay> out(channels);
  bool any = false;
  for (uint32_t c = 0; c < channels && c < 65536; ++c) {
    const std::string group = "DataSetInfo/Channel " + std::to_string(c);
    if (!exists(file, group)) continue;
    ChannelDisplay& d = out[c];
    if (const auto name = attr_string(file, group, "Name")) d.name = clean_channel_name(*name);
    if (const auto color = attr_string(file, group, "Color")) d.color = color_from_unit_floats(*color);
    if (const auto range = attr_string(file, group, "ColorRange")) {
      std::istringstream in(*range);
      double lo = 0, hi = 0;
      if (in >> lo >> hi && std::isfinite(lo) && std::isfinite(hi) && hi > lo) d.window = std::array<double, 2>{lo, hi};
    }
    any = any || !d.empty();
  }
  return any ? out : std::vector<ChannelDisplay>{};
}

std::string data_path(uint32_t t, uint32_t c) {
  return "DataSet/ResolutionLevel 0/TimePoint " + std::to_string(t) + "/Channel " + std::to_string(c) + "/Data";
}

hid_t mem_type(DType t) {
  switch (t) {
    case DType::kU8: return H5T_NATIVE_UINT8;
    case DType::kI8: return H5T_NATIVE_INT8;
    case DType::kU16: return H5T_NATIVE_UINT16;
    case DType::kI16: return H5T_NATIVE_INT16;
    case DType::kU32: return H5T_NATIVE_UINT32;
    case DType::kI32: return H5T_NATIVE_INT32;
    case DType::kF32: return H5T_NATIVE_FLOAT;
  }
  return H5T_NATIVE_UINT8;
}

class ImarisSource final : public SlabSource {
 public:
  ImarisSource(std::string path, hid_t file, VolumeInfo info, std::vector<std::string> warnings)
      : path_(std::move(path)), file_(file), info_(std::move(info)), warnings_(std::move(warnings)) {}
  ~ImarisSource() override {
    std::lock_guard<std::mutex> lock(hdf5_mutex());
    H5Fclose(file_);
  }
  const VolumeInfo& info() const override { return info_; }
  std::vector<std::string> warnings() const override { return warnings_; }
  std::string format_name() const override { return "Imaris (.ims)"; }
  std::vector<std::string> files() const override { return {path_}; }

  Status read_region(uint32_t channel, uint32_t timepoint, const Box3& box, std::span<uint8_t> dst) override {
    if (dst.size() != box.voxels() * dtype_bytes(info_.dtype)) return invalid_argument("read_region: wrong buffer size");
    if (channel >= info_.channels || timepoint >= info_.timepoints) return out_of_range("read_region: no such channel");
    for (int a = 0; a < 3; ++a)
      if (box.origin[a] + box.size[a] > info_.dims[a] || box.size[a] == 0)
        return out_of_range("read_region: box outside the volume");
    std::lock_guard<std::mutex> lock(hdf5_mutex());
    const std::string dp = data_path(timepoint, channel);
    Hid ds(H5Dopen2(file_, dp.c_str(), H5P_DEFAULT), H5Dclose);
    if (!ds.ok()) return corrupt(path_ + ": cannot open " + dp);
    Hid fspace(H5Dget_space(ds.get()), H5Sclose);
    const hsize_t start[3] = {box.origin[2], box.origin[1], box.origin[0]};
    const hsize_t count[3] = {box.size[2], box.size[1], box.size[0]};
    if (H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0)
      return corrupt(path_ + ": " + dp + " is smaller than ImageSize says");
    Hid mspace(H5Screate_simple(3, count, nullptr), H5Sclose);
    if (H5Dread(ds.get(), mem_type(info_.dtype), mspace.get(), fspace.get(), H5P_DEFAULT, dst.data()) < 0)
      return corrupt(path_ + ": cannot read " + dp + " (damaged data, or a compression filter this HDF5 lacks)");
    return Status::ok();
  }

 private:
  std::string path_;
  hid_t file_;
  VolumeInfo info_;
  std::vector<std::string> warnings_;
};

}  // namespace

bool has_hdf5_magic(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  char m[8] = {0};
  return f.read(m, 8) && std::memcmp(m, "\x89HDF\r\n\x1a\n", 8) == 0;
}

Result<std::unique_ptr<SlabSource>> open_imaris_import(const std::string& path) {
  std::lock_guard<std::mutex> lock(hdf5_mutex());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors come back as Status, not printed
  std::ifstream probe(path);
  if (!probe) return not_found(path + ": cannot open");
  if (!has_hdf5_magic(path)) return invalid_argument(path + ": not an HDF5/Imaris file (no HDF5 signature)");
  const hid_t fid = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (fid < 0) return corrupt(path + ": cannot open as HDF5; the file is truncated or damaged");
  struct Closer {
    hid_t id;
    bool keep = false;
    ~Closer() {
      if (!keep) H5Fclose(id);
    }
  } closer{fid};

  if (!exists(fid, "DataSet"))
    return corrupt(path + ": has no DataSet group; not an Imaris file, or a damaged one");
  if (!exists(fid, "DataSet/ResolutionLevel 0"))
    return corrupt(path + ": has no DataSet/ResolutionLevel 0; not an Imaris file, or a damaged one");
  VolumeInfo info;
  std::vector<std::string> warnings;
  uint32_t T = 0, C = 0;
  while (exists(fid, "DataSet/ResolutionLevel 0/TimePoint " + std::to_string(T))) ++T;
  if (T == 0) return corrupt(path + ": DataSet/ResolutionLevel 0 has no TimePoint 0");
  while (exists(fid, data_path(0, C))) ++C;
  if (C == 0) return corrupt(path + ": DataSet/ResolutionLevel 0/TimePoint 0 has no Channel 0/Data");
  for (uint32_t t = 0; t < T; ++t)
    for (uint32_t c = 0; c < C; ++c)
      if (!exists(fid, data_path(t, c))) return corrupt(path + ": " + data_path(t, c) + " is missing");
  info.channels = C;
  info.timepoints = T;

  // Stored (padded) shape and type from channel 0.
  Hid ds(H5Dopen2(fid, data_path(0, 0).c_str(), H5P_DEFAULT), H5Dclose);
  if (!ds.ok()) return corrupt(path + ": cannot open " + data_path(0, 0));
  Hid space(H5Dget_space(ds.get()), H5Sclose);
  hsize_t shape[3] = {0, 0, 0};
  if (H5Sget_simple_extent_ndims(space.get()) != 3) return corrupt(path + ": " + data_path(0, 0) + " is not 3D");
  H5Sget_simple_extent_dims(space.get(), shape, nullptr);
  Hid type(H5Dget_type(ds.get()), H5Tclose);
  const H5T_class_t cls = H5Tget_class(type.get());
  const size_t size = H5Tget_size(type.get());
  if (cls == H5T_INTEGER) {
    const bool s = H5Tget_sign(type.get()) == H5T_SGN_2;
    if (size == 1) info.dtype = s ? DType::kI8 : DType::kU8;
    else if (size == 2) info.dtype = s ? DType::kI16 : DType::kU16;
    else if (size == 4) info.dtype = s ? DType::kI32 : DType::kU32;
    else return unsupported(path + ": " + std::to_string(size * 8) + "-bit integer voxels are not supported");
  } else if (cls == H5T_FLOAT) {
    info.dtype = DType::kF32;
    if (size != 4) warnings.push_back(path + ": 64-bit float voxels are imported as 32-bit float");
  } else {
    return unsupported(path + ": voxel type of " + data_path(0, 0) + " is not an integer or float");
  }

  // Every dataset's compression filters must be available (LZ4 32004 often is not).
  for (uint32_t t = 0; t < T; ++t)
    for (uint32_t c = 0; c < C; ++c) {
      Hid d(H5Dopen2(fid, data_path(t, c).c_str(), H5P_DEFAULT), H5Dclose);
      Hid dcpl(H5Dget_create_plist(d.get()), H5Pclose);
      const int nf = dcpl.ok() ? H5Pget_nfilters(dcpl.get()) : 0;
      for (int i = 0; i < nf; ++i) {
        unsigned flags = 0, cd[8];
        size_t ncd = 8;
        char name[64] = {0};
        const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), unsigned(i), &flags, &ncd, cd, sizeof name, name, nullptr);
        if (id >= 0 && H5Zfilter_avail(id) <= 0) {
          if (id == kLz4Filter)
            return unsupported(path + ": is compressed with the HDF5 LZ4 filter (32004), which this HDF5 lacks; "
                               "install an LZ4 filter plugin and set HDF5_PLUGIN_PATH, or re-save it with gzip");
          return unsupported(path + ": needs HDF5 filter " + std::to_string(id) + " (" + name +
                             "), which this HDF5 lacks; install its plugin and set HDF5_PLUGIN_PATH");
        }
      }
    }

  // Image size: DataSetInfo/Image, else the channel group, else the dataset itself.
  const char* keys[3] = {"ImageSizeX", "ImageSizeY", "ImageSizeZ"};
  const std::string chan0 = "DataSet/ResolutionLevel 0/TimePoint 0/Channel 0";
  for (int a = 0; a < 3; ++a) {
    const hsize_t stored = shape[2 - a];
    std::optional<double> v = attr_number(fid, "DataSetInfo/Image", keys[a]);
    if (!v) v = attr_number(fid, chan0, keys[a]);
    if (!v) {
      v = double(stored);
      warnings.push_back(path + ": no " + keys[a] + " attribute; used the stored size " + std::to_string(stored));
    }
    if (!(*v >= 1) || *v > double(stored))
      return corrupt(path + ": " + keys[a] + " = " + std::to_string(*v) + " does not fit the stored data (" +
                     std::to_string(stored) + ")");
    info.dims[a] = uint64_t(*v);
  }

  // Voxel size from the extents.
  const auto unit_text = attr_string(fid, "DataSetInfo/Image", "Unit");
  const auto unit = unit_text ? parse_length_unit(*unit_text) : std::optional<LengthUnit>(LengthUnit{"um", 1.0});
  info.unit = unit ? unit->name : "um";
  for (int a = 0; a < 3; ++a) {
    const std::string n = std::to_string(a);
    const auto lo = attr_number(fid, "DataSetInfo/Image", ("ExtMin" + n).c_str());
    const auto hi = attr_number(fid, "DataSetInfo/Image", ("ExtMax" + n).c_str());
    if (lo && hi && *hi > *lo && std::isfinite(*hi - *lo)) {
      info.voxel_size[a] = (*hi - *lo) / double(info.dims[a]);
    } else {
      info.voxel_size[a] = 1.0;
      warnings.push_back(path + ": no usable ExtMin" + n + "/ExtMax" + n + "; voxel size along axis " + n + " set to 1");
    }
  }
  info.channel_display = imaris_channel_display(fid, info.channels);
  closer.keep = true;
  return std::unique_ptr<SlabSource>(new ImarisSource(path, fid, std::move(info), std::move(warnings)));
}

}  // namespace vxr
